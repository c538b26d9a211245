"""Project layer: the YAML project file, its checks, the static planner, importers."""

from ._checks import check
from ._importers import import_reconros, import_roslite
from ._launch_import import import_launch
from ._model import LoadedProject, Project, load_project
from ._planner import plan, plan_file
from ._report import CheckReport
from ._ros_scan import ros_template, writes_ros
from ._scan import scan_file
from ._template import template_from_sources

__all__ = [
    "CheckReport",
    "LoadedProject",
    "Project",
    "check",
    "import_launch",
    "import_reconros",
    "import_roslite",
    "load_project",
    "plan",
    "plan_file",
    "ros_template",
    "scan_file",
    "template_from_sources",
    "writes_ros",
]

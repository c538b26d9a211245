"""Project layer: the YAML project file, its checks, the static planner, importers."""

from ._checks import check
from ._importers import import_reconros, import_roslite
from ._model import LoadedProject, Project, load_project
from ._planner import plan, plan_file
from ._report import CheckReport
from ._scan import scan_file
from ._template import template_from_sources

__all__ = [
    "CheckReport",
    "LoadedProject",
    "Project",
    "check",
    "import_reconros",
    "import_roslite",
    "load_project",
    "plan",
    "plan_file",
    "scan_file",
    "template_from_sources",
]

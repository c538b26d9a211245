"""Project layer: the YAML project file, its checks, the static planner, importers."""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports
from ._checks import check
from ._importers import import_reconros, import_roslite
from ._launch_import import import_launch
from ._model import LoadedProject, Project, load_project
from ._planner import plan, plan_file
from ._report import CheckReport
from ._ros_scan import data_files, ros_template, writes_ros
from ._scan import scan_file
from ._template import template_from_sources

if TYPE_CHECKING:
    from ._graph import describe, render_svg, write_graph
    from ._reference import reference_markdown


# shared with other packages, loaded on first use (a worker must not pay for what it does not run)
_LAZY = {
    "describe": "._graph",
    "reference_markdown": "._reference",
    "render_svg": "._graph",
    "write_graph": "._graph",
}


__getattr__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "CheckReport",
    "LoadedProject",
    "Project",
    "check",
    "data_files",
    "describe",
    "import_launch",
    "import_reconros",
    "import_roslite",
    "load_project",
    "plan",
    "plan_file",
    "reference_markdown",
    "render_svg",
    "ros_template",
    "scan_file",
    "template_from_sources",
    "write_graph",
    "writes_ros",
]

"""launch_xml.launch_description_sources: a XML launch file, read by hetros's importer in place."""

from ..launch.launch_description_sources import FrontendLaunchDescriptionSource as XMLLaunchDescriptionSource

__all__ = ["XMLLaunchDescriptionSource"]

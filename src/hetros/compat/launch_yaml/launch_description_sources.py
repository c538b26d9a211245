"""launch_yaml.launch_description_sources: a YAML launch file, read by hetros's importer in place."""

from ..launch.launch_description_sources import FrontendLaunchDescriptionSource as YAMLLaunchDescriptionSource

__all__ = ["YAMLLaunchDescriptionSource"]

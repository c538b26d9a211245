"""launch.utilities: the helpers launch files call on substitutions."""

from ._core import normalize_to_list_of_substitutions, perform_substitutions

__all__ = ["normalize_to_list_of_substitutions", "perform_substitutions"]

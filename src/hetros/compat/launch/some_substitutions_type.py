"""launch.some_substitutions_type: the type of what a substitution argument takes."""

from ._core import SomeSubstitutionsType, SomeSubstitutionsType_types_tuple

__all__ = ["SomeSubstitutionsType", "SomeSubstitutionsType_types_tuple"]

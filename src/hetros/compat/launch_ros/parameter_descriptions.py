"""launch_ros.parameter_descriptions: as launch_ros.descriptions names them."""

from .descriptions import Parameter, ParameterFile, ParameterValue

__all__ = ["Parameter", "ParameterFile", "ParameterValue"]

"""The compiled codec (``hetros.msg._ccdr``): built where a C compiler is, skipped otherwise.

Everything else about the package is in pyproject.toml. ``optional=True`` lets an install
without a compiler go on: hetros then uses its generated pure-Python codecs.
"""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "hetros.msg._ccdr",
            sources=["src/hetros/msg/_ccdr.c"],
            extra_compile_args=["-O2", "-std=c11", "-Wall", "-Wextra", "-Wno-missing-field-initializers",
                                "-Wno-cast-function-type"],
            optional=True,
        )
    ]
)

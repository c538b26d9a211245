"""hetros' compiled hot path: built where a C compiler is, skipped otherwise.

``hetros.msg._ccdr`` interprets per-type codec programs; ``hetros.transport.shm._cslot`` gives
shared-memory slots as buffers; ``hetros.compat.tf2_py._ctf`` walks the transform tree. Everything else about the package is in pyproject.toml.
``optional=True`` lets an install without a compiler go on: hetros then runs its pure-Python
path (generated codecs, ctypes views), which ``HETROS_PURE_PYTHON=1`` also selects.
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
        ),
        Extension(
            "hetros.compat.tf2_py._ctf",
            sources=["src/hetros/compat/tf2_py/_ctf.c"],
            extra_compile_args=["-O2", "-std=c11", "-Wall", "-Wextra", "-Wno-missing-field-initializers"],
            optional=True,
        ),
        Extension(
            "hetros.transport.shm._cslot",
            sources=["src/hetros/transport/shm/_cslot.c"],
            extra_compile_args=["-O2", "-std=c11", "-Wall", "-Wextra", "-Wno-missing-field-initializers"],
            optional=True,
        ),
    ]
)

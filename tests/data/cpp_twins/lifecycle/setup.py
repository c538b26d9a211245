"""The C++ lifecycle demo's executables, as Python twins: what hetros's tests run for launch files naming them."""

from setuptools import setup

package_name = 'lifecycle'

setup(
    name=package_name,
    version='0.0.0',
    packages=['cpp_twins_lifecycle'],
    entry_points={
        'console_scripts': [
            'lifecycle_talker = lifecycle_py.talker:main',
            'lifecycle_listener = cpp_twins_lifecycle.lifecycle_listener:main',
            'lifecycle_service_client = cpp_twins_lifecycle.lifecycle_service_client:main',
        ],
    },
)

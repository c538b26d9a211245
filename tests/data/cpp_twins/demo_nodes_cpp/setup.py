"""demo_nodes_cpp's executables, as Python twins: what hetros's tests run for launch files naming them."""

from setuptools import setup

package_name = 'demo_nodes_cpp'

setup(
    name=package_name,
    version='0.0.0',
    packages=['cpp_twins'],
    entry_points={
        'console_scripts': [
            'talker = demo_nodes_py.topics.talker:main',
            'listener = demo_nodes_py.topics.listener:main',
            'listener_best_effort = cpp_twins.listener_best_effort:main',
            'add_two_ints_server = demo_nodes_py.services.add_two_ints_server:main',
            'add_two_ints_client = demo_nodes_py.services.add_two_ints_client:main',
            'add_two_ints_client_async = demo_nodes_py.services.add_two_ints_client_async:main',
        ],
    },
)

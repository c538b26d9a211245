"""composition's components, as Python twins: what hetros's tests load for ComposableNode(package='composition')."""

from setuptools import setup

package_name = 'composition'

setup(
    name=package_name,
    version='0.0.0',
    packages=['cpp_twins_composition'],
    entry_points={
        'rclpy_components': [
            'composition::Talker = cpp_twins_composition.talker_component:Talker',
            'composition::Listener = cpp_twins_composition.listener_component:Listener',
        ],
    },
)

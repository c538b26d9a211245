"""Existing ROS code, unchanged, as hetros nodes: ``import rclpy`` and ``from std_msgs.msg import String``
inside hetros's processes.

A node file written for rclpy keeps its ``main()``; the project names it (``run:
pkg.module:main``) and hetros calls it in the node's thread with that node bound
(``_context``), so ``rclpy.init``, ``Node('talker')`` and ``rclpy.spin`` work on the
node the plan wired. The names ``rclpy`` and ROS message packages (``std_msgs.msg``)
are served by a finder that hetros installs in its own processes only (:func:`install`),
in front of the environment's: a real rclpy installed beside hetros is not shadowed
anywhere else.
"""

from ._importer import install

__all__ = ["install"]

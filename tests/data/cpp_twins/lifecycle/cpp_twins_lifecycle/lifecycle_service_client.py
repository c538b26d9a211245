"""A Python port of ros2/demos's lifecycle_service_client (C++): it walks the managed talker through
configure, activate, deactivate, activate, deactivate, cleanup and shutdown, reading its state after
each, as the C++ client does (2 s apart here, 10 s there)."""

import time

import rclpy
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.node import Node

NODE = 'lc_talker'
BETWEEN_STATE_CHANGES = 2.0


class LifecycleServiceClient(Node):

    def __init__(self, node_name):
        super().__init__(node_name)
        self.client_get_state = self.create_client(GetState, '/lc_talker/get_state')
        self.client_change_state = self.create_client(ChangeState, '/lc_talker/change_state')

    def get_state(self, timeout=3.0):
        if not self.client_get_state.wait_for_service(timeout_sec=timeout):
            self.get_logger().error('Service %s is not available.' % self.client_get_state.srv_name)
            return None
        future = self.client_get_state.call_async(GetState.Request())
        rclpy.spin_until_future_complete(self, future, timeout_sec=timeout)
        if not future.done():
            self.get_logger().error('Server time out while getting current state for node %s' % NODE)
            return None
        state = future.result().current_state
        self.get_logger().info('Node %s has current state %s.' % (NODE, state.label))
        return state.id

    def change_state(self, transition, timeout=3.0):
        if not self.client_change_state.wait_for_service(timeout_sec=timeout):
            self.get_logger().error('Service %s is not available.' % self.client_change_state.srv_name)
            return False
        future = self.client_change_state.call_async(ChangeState.Request(transition=Transition(id=transition)))
        rclpy.spin_until_future_complete(self, future, timeout_sec=timeout)
        if not future.done():
            self.get_logger().error('Server time out while changing state for node %s' % NODE)
            return False
        if future.result().success:
            self.get_logger().info('Transition %d successfully triggered.' % transition)
            return True
        self.get_logger().warning('Failed to trigger transition %d' % transition)
        return False


def callee_script(client):
    for transition in (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_ACTIVATE,
                       Transition.TRANSITION_DEACTIVATE, Transition.TRANSITION_ACTIVATE,
                       Transition.TRANSITION_DEACTIVATE, Transition.TRANSITION_CLEANUP,
                       Transition.TRANSITION_UNCONFIGURED_SHUTDOWN):
        if not rclpy.ok():
            return
        time.sleep(BETWEEN_STATE_CHANGES)
        if not client.change_state(transition):
            return
        if client.get_state() is None:
            return


def main(args=None):
    rclpy.init(args=args)
    client = LifecycleServiceClient('lc_client')
    client.get_state()
    callee_script(client)
    client.destroy_node()
    rclpy.try_shutdown()

"""A std_srvs/SetBool service that answers success = data, for ROS 1 clients to call."""

from hetros import Node
from hetros.interfaces.std_srvs.srv import SetBool


def set_bool(node: Node) -> None:
    def answer(request: SetBool.Request) -> SetBool.Response:
        node.log.info("set_bool(%s)", request.data)
        return SetBool.Response(success=request.data, message=f"set to {request.data}")

    node.create_service(SetBool, "/set_bool", answer)

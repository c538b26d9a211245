"""A service and a client: the client asks /add_two_ints and logs the sums."""

from hetros import Node
from hetros.interfaces.example_interfaces.srv import AddTwoInts


def server(node: Node) -> None:
    def add(request: AddTwoInts.Request) -> AddTwoInts.Response:
        node.log.info("Incoming request: a=%d b=%d", request.a, request.b)
        return AddTwoInts.Response(sum=request.a + request.b)

    node.create_service(AddTwoInts, "/add_two_ints", add)


def client(node: Node) -> None:
    add = node.create_client(AddTwoInts, "/add_two_ints")
    for i in range(node.get_parameter("calls", 5)):
        response = add.call(AddTwoInts.Request(a=i, b=10 * i), timeout=10.0)
        node.log.info("Result of add_two_ints: %d + %d = %d", i, 10 * i, response.sum)

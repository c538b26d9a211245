"""Node functions the project-file cases refer to."""


def talker(node: object) -> None:
    del node


not_callable = 42


def chatter_as_int(node: object) -> None:
    """Publishes /chatter as Int32, where the project declares String."""
    from hetros.interfaces.std_msgs.msg import Int32

    node.create_publisher(Int32, "/chatter")  # type: ignore[attr-defined]


def chatter_typo(node: object) -> None:
    """Publishes /chater: the project declares /chatter."""
    from hetros.interfaces.std_msgs.msg import String

    node.create_publisher(String, "/chater")  # type: ignore[attr-defined]

"""Node functions the project-file cases refer to."""


def talker(node: object) -> None:
    del node


not_callable = 42

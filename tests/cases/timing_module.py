"""A node that passes a parameter to rate(): tests/unit/test_plan_rules.py gives it one that cannot be a rate."""


def main(node):  # type: ignore[no-untyped-def]
    for _ in node.rate(node.get_parameter("hz", 10.0)):
        break

"""Quality of service, with one meaning on every transport.

* reliable + keep_all: a bounded FIFO of ``depth`` per subscriber; a full FIFO
  blocks the publisher, for at most ``publish_timeout`` seconds, then
  :class:`~hetros.PublishTimeoutError` (fpgaDDS's Reliable/Keep-All default).
* keep_last (or best_effort): the FIFO keeps the newest ``depth`` messages,
  dropping the oldest; the publisher never blocks.
* transient_local: a subscriber that joins late first gets the last ``depth``
  messages each publisher sent.
* deadline: each publisher publishes, and each subscriber receives, at least once
  per ``deadline`` seconds; a miss is reported to the node (``on_deadline_missed``).
* lifespan: a message older than ``lifespan`` seconds when it would be taken is
  dropped (counted) instead of delivered.
* liveliness: a publisher is alive while its process is (``automatic``), or while it
  publishes or calls ``assert_liveliness`` at least once per ``lease_duration``
  (``manual_by_topic``); a subscriber learns when a publisher's liveliness is lost or
  regained (``on_liveliness_changed``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal

from annotated_types import Ge, Gt, Le
from typing_extensions import Doc

MAX_DEPTH = 1_000_000
Reliability = Literal["reliable", "best_effort"]
History = Literal["keep_all", "keep_last"]
Durability = Literal["volatile", "transient_local"]
Liveliness = Literal["automatic", "manual_by_topic"]


@dataclass(frozen=True, kw_only=True)
class QoS:
    """Per-topic quality of service. Construct with keywords or use a preset.

    The one definition: the project file's ``topics:`` entries are validated as this class.
    """

    # read by pydantic where the project file is validated; a plain dict, so that loading QoS
    # (every worker does) does not load pydantic
    __pydantic_config__: ClassVar[dict[str, str]] = {"extra": "forbid"}

    # Annotated bounds: the project file's errors then name the field (topics./x.depth); Doc: its
    # line in the project file's reference (docs/PROJECT_FILE.md)
    reliability: Annotated[Reliability, Doc("best_effort never blocks the publisher and may drop")] = "reliable"
    history: Annotated[History, Doc("keep_all blocks a reliable publisher while a FIFO is full; keep_last "
                                    "drops the oldest")] = "keep_all"
    depth: Annotated[int, Ge(1), Le(MAX_DEPTH), Doc("the FIFO of each subscriber, in messages")] = 10
    durability: Annotated[Durability, Doc("transient_local replays the last depth messages to a late "
                                          "subscriber")] = "volatile"
    publish_timeout: Annotated[float, Gt(0), Doc("seconds a reliable keep_all publisher waits for room before "
                                                 "PublishTimeoutError")] = 5.0
    hw_fifo: Annotated[int, Ge(3), Le(1 << 20), Doc("fpga targets: a FIFO of this many beats in front of each "
                                                    "subscriber (absent: none)")] | None = None
    deadline: Annotated[float, Gt(0), Doc("seconds: each publisher publishes, each subscriber receives, at least "
                                          "once a period (absent: none)")] | None = None
    lifespan: Annotated[float, Gt(0), Doc("seconds after which an untaken message is dropped (absent: "
                                          "never)")] | None = None
    liveliness: Annotated[Liveliness, Doc("manual_by_topic: alive while it publishes or asserts within "
                                          "lease_duration")] = "automatic"
    lease_duration: Annotated[float, Gt(0), Doc("seconds of the liveliness lease (absent: "
                                                "infinite)")] | None = None

    def __post_init__(self) -> None:
        if self.reliability not in ("reliable", "best_effort"):
            raise ValueError(f"reliability must be 'reliable' or 'best_effort', not {self.reliability!r}")
        if self.history not in ("keep_all", "keep_last"):
            raise ValueError(f"history must be 'keep_all' or 'keep_last', not {self.history!r}")
        if self.durability not in ("volatile", "transient_local"):
            raise ValueError(f"durability must be 'volatile' or 'transient_local', not {self.durability!r}")
        if not isinstance(self.depth, int) or not 1 <= self.depth <= MAX_DEPTH:
            raise ValueError(f"depth must be an integer from 1 to {MAX_DEPTH:,}, not {self.depth!r}")
        if self.hw_fifo is not None and not (isinstance(self.hw_fifo, int) and 3 <= self.hw_fifo <= 1 << 20):
            raise ValueError(f"hw_fifo must be 3 to {1 << 20:,} beats (a FIFO of 2 runs at half rate), "
                             f"not {self.hw_fifo!r}")
        if not self.publish_timeout > 0:
            raise ValueError(f"publish_timeout must be positive seconds, not {self.publish_timeout!r}")
        for name in ("deadline", "lifespan", "lease_duration"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, int | float) and value > 0):
                raise ValueError(f"{name} must be positive seconds (or absent: none), not {value!r}")
        if self.liveliness not in ("automatic", "manual_by_topic"):
            raise ValueError(f"liveliness must be 'automatic' or 'manual_by_topic', not {self.liveliness!r}")

    @property
    def blocks_publisher(self) -> bool:
        """Whether a full subscriber FIFO makes the publisher wait (else the oldest is dropped)."""
        return self.reliability == "reliable" and self.history == "keep_all"

    @property
    def keeps_history(self) -> bool:
        return self.durability == "transient_local"

    # Presets, named after what they are for.
    @classmethod
    def reliable(cls, depth: int = 10) -> QoS:
        return cls(depth=depth)

    @classmethod
    def sensor_data(cls, depth: int = 5) -> QoS:
        return cls(reliability="best_effort", history="keep_last", depth=depth)

    @classmethod
    def latest(cls, depth: int = 1) -> QoS:
        return cls(history="keep_last", depth=depth)

    @classmethod
    def latched(cls, depth: int = 1) -> QoS:
        return cls(history="keep_last", depth=depth, durability="transient_local")


DEFAULT_QOS = QoS()

# a timer's or a rate's period, in seconds: from a nanosecond (a billion Hz) to about four months. Below the
# layers because the checks refuse a parameter the code passes to a timer by the bounds the runtime enforces.
MIN_PERIOD, MAX_PERIOD = 1e-9, 1e7

# the policies ROS 2 matches an offer against a request by, in the order it reports them
MATCHED_POLICIES = ("reliability", "durability", "deadline", "liveliness", "lease_duration")
# how strong each kind is: the offer must be at least as strong as the request
_RANK = {"best_effort": 0, "reliable": 1, "volatile": 0, "transient_local": 1, "automatic": 0, "manual_by_topic": 1}
_PERIODS = ("deadline", "lease_duration")  # seconds; None is infinite; the offer must be at most the request


def offer_falls_short(policy: str, offered: object, requested: object) -> bool:
    """Whether a publisher offering ``offered`` for ``policy`` cannot serve a subscription requesting
    ``requested``, as ROS 2 matches them (kinds by strength, periods by length, None infinite)."""
    if policy in _PERIODS:
        return requested is not None and (offered is None or float(offered) > float(requested))  # type: ignore[arg-type]
    return _RANK[str(requested)] > _RANK[str(offered)]


def incompatible_policy(offered: QoS, requested: QoS) -> str | None:
    """The first policy (``MATCHED_POLICIES``) by which ``offered`` cannot serve ``requested``, or None
    when they match."""
    for policy in MATCHED_POLICIES:
        if offer_falls_short(policy, getattr(offered, policy), getattr(requested, policy)):
            return policy
    return None


# the policies that decide how a topic delivers: a topic's QoS from the project file applies to every endpoint,
# so code that chose otherwise for one of these would get what it did not ask for
DELIVERY_POLICIES = ("reliability", "durability", "history")


def delivery_conflicts(chosen: dict[str, str], declared: QoS, subscription: bool) -> list[str]:
    """Each policy of ``chosen`` (what the code asked for, policy -> value) that the topic's QoS contradicts,
    as ``policy value (the project file: value)``. A subscription that gets a stronger reliability or
    durability than it asked (ROS 2 matches those) is no conflict."""
    found = []
    for policy in DELIVERY_POLICIES:
        if policy not in chosen or chosen[policy] == getattr(declared, policy):
            continue
        if subscription and policy != "history" and \
                offer_falls_short(policy, getattr(declared, policy), chosen[policy]) is False:
            continue
        found.append(f"{policy} {chosen[policy]} (the project file: {getattr(declared, policy)})")
    return found

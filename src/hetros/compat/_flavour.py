"""rclpy's message flavour on hetros's message classes: numeric sequences as ``array.array``.

rclpy gives an unbounded or bounded numeric sequence (``int32[]``, ``float64[<=8]``) as an
``array.array`` (``msg.sequence.append(1)``; printed ``array('i', [0, 1])``); fixed arrays are
numpy arrays in both. hetros keeps numpy arrays, which travel without copies. The rclpy code
hetros runs sees rclpy's flavour where it can tell the difference:

* messages it constructs are of a thin subclass (same slots, same ``__msgtype__``) that prints as
  rclpy's messages print (``std_msgs.msg.String(data='hi')``, numeric sequences as lists), turns a
  list assigned to a numeric sequence into an ``array.array``, and starts it as an empty one;
* replies, goals, feedback and results it receives keep their numpy arrays, shown through
  :class:`SequenceView`, a zero-copy view that prints as ``array.array`` does, and print as
  rclpy's. A topic's message is not shown so: on that hot path the view would cost a quarter of a
  small message's one-way latency; its arrays are hetros's read-only numpy arrays, and it prints as
  hetros's messages do.

Replies, goals, feedback and results are copied into hetros's own class first. A topic's message is
published as the caller made it, unsealed (``Publisher.publish(keep=True)``): every transport between
processes serializes it before the publish returns, the flavoured class encodes as its base does, and
only an in-process subscriber, which would hold the object, gets a copy."""

from __future__ import annotations

import array
import dataclasses
import functools
from collections.abc import Callable
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype

from ..msg import ActionType, ServiceType, init_source, registry
from ..runtime import check_type

# array.array's type codes, as rclpy picks them per ROS type
_TYPECODES = {"int8": "b", "uint8": "B", "byte": "B", "char": "B", "int16": "h", "uint16": "H", "int32": "i",
              "uint32": "I", "int64": "q", "uint64": "Q", "float32": "f", "float64": "d"}

_DTYPE_CODES = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "i8": "q", "u8": "Q", "f4": "f",
                "f8": "d"}


class SequenceView(np.ndarray):
    """A received numeric sequence: the message's numpy array, printed as rclpy's ``array.array``."""

    @property
    def typecode(self) -> str:
        return _DTYPE_CODES.get(self.dtype.str[1:], self.dtype.char)

    def copy(self, order: Any = "C") -> np.ndarray[Any, Any]:  # type: ignore[override]
        """A plain numpy copy: what a copied message holds (hetros's compiled codec takes exactly numpy's)."""
        return np.array(self, order=order)

    def __repr__(self) -> str:
        values = self.tolist()
        return f"array({self.typecode!r}, {values!r})" if values else f"array({self.typecode!r})"

    __str__ = __repr__


@functools.cache  # asked per received service or action message (received) and per repr: read once per type
def _sequences(typename: str) -> dict[str, str]:
    """The numeric sequence fields of ``typename`` and their type codes."""
    found = {}
    for name, desc in registry().fielddefs[typename][1]:
        if desc[0] == Nodetype.SEQUENCE and desc[1][0][0] == Nodetype.BASE and desc[1][0][1][0] in _TYPECODES:
            found[name] = _TYPECODES[desc[1][0][1][0]]
    return found


@functools.cache
def _nested(typename: str) -> dict[str, tuple[str, bool]]:
    """The message-typed fields of ``typename``: name -> (type, whether a list of them)."""
    found = {}
    for name, desc in registry().fielddefs[typename][1]:
        if desc[0] == Nodetype.NAME:
            found[name] = (str(desc[1]), False)
        elif desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE) and desc[1][0][0] == Nodetype.NAME:
            found[name] = (str(desc[1][0][1]), True)
    return found


_classes: dict[type[Any], type[Any]] = {}
_made: set[type[Any]] = set()  # the flavoured classes themselves


def _shown(value: Any) -> Any:
    return value.view(SequenceView) if type(value) is np.ndarray else value


def _stored_sequence(code: str) -> Callable[[Any], Any]:
    """What a numeric sequence field stores of a value, as rclpy converts it (a list becomes an
    ``array.array``; an array is kept, plain, so that it travels without a copy)."""

    def stored(value: Any) -> Any:
        kind = type(value)
        if kind is SequenceView:
            return value.view(np.ndarray)
        if kind is np.ndarray:
            if not value.size and value.flags.writeable:
                return array.array(code)  # a new message's empty sequence, ready to append to
            return value
        if kind is array.array:
            return value
        return value.view(np.ndarray) if isinstance(value, np.ndarray) else array.array(code, value)

    return stored


def _sequence_property(base: type[Any], name: str, code: str) -> property:
    """A numeric sequence over ``base``'s slot: read through :class:`SequenceView`, written as rclpy converts."""
    slot = _slot(base, name)
    read, write = slot.__get__, slot.__set__
    stored = _stored_sequence(code)

    def get(self: Any) -> Any:
        return _shown(read(self, None))

    def put(self: Any, value: Any) -> None:
        # a filled numpy array, what a publisher's data usually is, without another call
        write(self, value if type(value) is np.ndarray and value.size else stored(value))

    return property(get, put)


def _flavoured_init(cls: type[Any], sequences: dict[str, str]) -> Callable[..., None]:
    """``cls``'s generated constructor with its numeric sequences stored as rclpy stores them, straight into
    their slots: through the sequence properties the base's constructor cost a new Image 0.45 µs more than
    hetros's own, on the path of every message rclpy code publishes."""
    spec = cls._hetros_init
    namespace = {**spec.namespace, "_A": array.array}
    stores = {}
    for name, code in sequences.items():
        namespace[f"_S_{name}"] = _slot(cls, name).__set__
        namespace[f"_C_{name}"] = _stored_sequence(code)
        stores[name] = (f"_S_{name}(_m, _A({code!r}) if {name} is _U or {name} is None "
                        f"else _C_{name}({{value}}))")
    source = "\n".join(init_source(spec.fields, stores))
    exec(compile(source, f"<hetros rclpy-flavoured message {cls.__msgtype__}>", "exec"), namespace)
    init: Callable[..., None] = namespace["__init__"]
    return init


def _slot(cls: type[Any], name: str) -> Any:
    """The slot that stores field ``name`` of ``cls`` (a flavoured class's sequence property stands in front
    of it)."""
    return next(k.__dict__[name] for k in cls.__mro__ if name in k.__dict__ and not isinstance(k.__dict__[name],
                                                                                                property))


def rclpy_repr(message: Any) -> str:
    """A message as rclpy's generated ``__repr__`` shows it: ``example_interfaces.action.Fibonacci_Result(
    sequence=[0, 1, 1])``, numeric sequences as lists (``[]`` when empty), messages inside in the same form."""
    typename = message.__msgtype__
    numeric = _sequences(typename)
    shown = ", ".join(f"{name}={_field_repr(getattr(message, name), name in numeric)}"
                      for name in message.__fieldnames__)
    return f"{typename.replace('/', '.')}({shown})"


def _field_repr(value: Any, numeric_sequence: bool) -> str:
    if numeric_sequence:
        return repr(value.tolist()) if len(value) else "[]"
    if getattr(value, "__msgtype__", None):
        return rclpy_repr(value)
    if isinstance(value, list) and value and getattr(value[0], "__msgtype__", None):
        return f"[{', '.join(rclpy_repr(item) for item in value)}]"
    return repr(value)


def flavoured(cls: type[Any]) -> type[Any]:
    """``cls`` as rclpy code constructs it: a subclass that prints as rclpy's messages do and, for a type with
    numeric sequences, holds them as rclpy does. The subclass adds no storage, so hetros's compiled codec
    copies and encodes it as ``cls`` itself."""
    if cls in _classes:
        return _classes[cls]
    sequences = _sequences(cls.__msgtype__)
    members: dict[str, Any] = {name: _sequence_property(cls, name, code) for name, code in sequences.items()}
    if sequences and getattr(cls, "_frozen_class", None) is not cls:
        members["__init__"] = _flavoured_init(cls, sequences)
    made: Any = type(cls.__name__, (cls,), {"__slots__": (), "__module__": cls.__module__,
                                            "__qualname__": cls.__qualname__, "__repr__": rclpy_repr,
                                            "__str__": rclpy_repr, **members})
    if getattr(cls, "_frozen_class", None) is cls:
        made._frozen_class = made  # a received read-only message stays read-only (``is_frozen``)
    _classes[cls] = _classes[made] = made
    _made.add(made)
    return _classes[cls]


def flavoured_service(service: ServiceType) -> ServiceType:
    return dataclasses.replace(service, Request=flavoured(service.Request), Response=flavoured(service.Response))


def flavoured_action(action: ActionType) -> ActionType:
    return dataclasses.replace(action, Goal=flavoured(action.Goal), Result=flavoured(action.Result),
                               Feedback=flavoured(action.Feedback),
                               SendGoal=flavoured_service(action.SendGoal),
                               GetResult=flavoured_service(action.GetResult),
                               FeedbackMessage=flavoured(action.FeedbackMessage))


def served(value: Any) -> Any:
    """What a served interface module holds for ``value`` of a hetros one: types flavoured, the rest as is."""
    if isinstance(value, ActionType):
        return flavoured_action(value)
    if isinstance(value, ServiceType):
        return flavoured_service(value)
    if isinstance(value, type) and getattr(value, "__msgtype__", None):
        return flavoured(value)
    return value


Viewer = Callable[[Any], None]
_viewers: dict[str, Viewer | None] = {}


def viewer(typename: str) -> Viewer | None:
    """What shows a received ``typename``'s numeric sequences as :class:`SequenceView`; None when it has none
    (nor have the messages inside it), so most types cost nothing."""
    if typename in _viewers:
        return _viewers[typename]
    _viewers[typename] = None  # a type that contains itself is refused by the registry; this ends the walk
    sequences = list(_sequences(typename))
    inner = [(name, nested_viewer, many) for name, (nested, many) in _nested(typename).items()
             if (nested_viewer := viewer(nested)) is not None]
    if not sequences and not inner:
        return None

    cls = registry().get(typename)
    slots = [(next(k.__dict__[n] for k in cls.__mro__ if n in k.__dict__)) for n in sequences]
    fields = [(slot.__get__, slot.__set__) for slot in slots]

    def show(message: Any) -> None:
        for read, write in fields:
            value = read(message, None)
            if type(value) is np.ndarray:
                write(message, value.view(SequenceView))  # a frozen message too: it is its field's view
        for name, nested_viewer, many in inner:
            value = getattr(message, name)
            for item in (value if many else (value,)):
                nested_viewer(item)
    _viewers[typename] = show
    return show


def copied(value: Any, expected: type[Any], where: str) -> Any:
    """A writable copy of ``value``, which ROS code keeps after handing it over (a publish, a request, a
    goal, feedback, a result); a TopicTypeError (a TypeError, as rclpy raises) naming ``where`` and the
    type it carries when ``value`` is no message of type ``expected``: a ``str`` or ``None`` would fail
    inside the copy with an AttributeError that says nothing of either."""
    try:
        return type(value)._hetros_copy(value)
    except AttributeError:
        check_type(value, str(expected.__msgtype__), where)
        raise


_keepers: dict[type[Any], Callable[[Any], bool]] = {}


def keepable(cls: type[Any]) -> Callable[[Any], bool]:
    """Whether a message of ``cls`` a shim publishes may go as it is (``Publisher.publish(keep=True)``:
    the transports serialize it, the caller keeps it): where its numeric sequences are numpy arrays,
    which every codec reads as they are. A sequence rclpy-style in an ``array.array``, or numeric
    sequences inside nested messages (a walk per publish would cost more than the copy), go through
    :func:`copied`. Asked once per class, then once per publish: rclpy code that publishes a large
    image no longer pays a copy of its own."""
    found = _keepers.get(cls)
    if found is None:
        found = _keepers[cls] = _keeper(cls)
    return found


def _keeper(cls: type[Any]) -> Callable[[Any], bool]:
    typename = getattr(cls, "__msgtype__", None)
    if not isinstance(typename, str) or typename not in registry().fielddefs or \
            any(_nested_sequences(nested) for nested, _ in _nested(typename).values()):
        return lambda _message: False
    reads = [_slot(cls, name).__get__ for name in _sequences(typename)]
    if not reads:
        return lambda _message: True
    if len(reads) == 1:
        (read,) = reads
        return lambda message: type(read(message, None)) is not array.array
    return lambda message: all(type(read(message, None)) is not array.array for read in reads)


@functools.cache
def _nested_sequences(typename: str) -> bool:
    """Whether ``typename`` or a message inside it has a numeric sequence."""
    return bool(_sequences(typename)) or any(_nested_sequences(t) for t, _ in _nested(typename).values())


def received(message: Any) -> Any:
    """``message`` (as a transport delivered it) shown in rclpy's flavour: its numeric sequences as views, and
    of the flavoured class (so that it prints as rclpy's messages do)."""
    show = viewer(message.__msgtype__)
    if show is not None:
        show(message)
    _reclass(message)
    return message


def _reclass(message: Any) -> None:
    """Make ``message`` and the messages inside it of their flavoured classes (a read-only one stays so)."""
    if type(message) in _made:
        return
    object.__setattr__(message, "__class__", flavoured(type(message)))  # a read-only one refuses plain sets
    for name, (_, many) in _nested(message.__msgtype__).items():
        value = getattr(message, name)
        for item in (value if many else (value,)):
            _reclass(item)

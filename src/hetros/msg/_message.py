"""The base class of every generated message type.

A message handed to subscribers is *frozen*: its class is swapped for a
read-only twin and its numpy arrays are made non-writeable. Swapping the class
costs nothing at construction time (plain messages keep the fast generated
``__init__``) and makes accidental writes fail loudly instead of silently
changing what another subscriber sees.
"""

from __future__ import annotations

import copy as _copy
import weakref
from typing import Any, ClassVar

import numpy as np

from .._errors import ReadOnlyMessageError


class Message:
    """Base of all message classes; concrete classes are generated per type."""

    # the loan a transport handed out with this message: it lives and dies with the message,
    # so an abandoned loan returns its slot when the message is garbage-collected
    __slots__ = ("_hetros_loan",)
    __msgtype__: ClassVar[str] = ""
    __fieldnames__: ClassVar[tuple[str, ...]] = ()
    _frozen_class: ClassVar[type[Message]]
    _thawed_class: ClassVar[type[Message]]
    # what freeze() must visit, fixed per type when the class is generated
    _array_names: ClassVar[tuple[str, ...]] = ()
    _nested_names: ClassVar[tuple[str, ...]] = ()
    _nested_list_names: ClassVar[tuple[str, ...]] = ()
    _list_names: ClassVar[tuple[str, ...]] = ()

    @staticmethod
    def _hetros_validate(message: Any, where: str = "") -> None:
        """Replaced per type by the registry's generated validator."""

    def copy(self) -> Any:
        """Return a deep, writable copy (use it to keep a delivered message).

        A message type with a field named ``copy`` hides this method (the field wins, as
        in ROS 2); :func:`hetros.msg.copy` works for every type.
        """
        return copy(self)

    @property
    def is_frozen(self) -> bool:
        return type(self) is self._frozen_class

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Message) or other.__msgtype__ != self.__msgtype__:
            return NotImplemented
        for name in self.__fieldnames__:
            mine, theirs = getattr(self, name), getattr(other, name)
            if isinstance(mine, np.ndarray) or isinstance(theirs, np.ndarray):
                if not np.array_equal(np.asarray(mine), np.asarray(theirs)):
                    return False
            elif mine != theirs:
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        fields = ", ".join(f"{n}={_short_repr(getattr(self, n))}" for n in self.__fieldnames__)
        return f"{self.__msgtype__.rsplit('/', 1)[-1]}({fields})"

    def __deepcopy__(self, memo: dict[int, Any]) -> Any:
        return copy(self)


class FrozenMessage(Message):
    """Mixin for the read-only twin of a message class."""

    __slots__ = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise ReadOnlyMessageError(
            f"{self.__msgtype__}.{name} cannot be set: this message was handed over "
            "without a copy (published, or delivered to a subscriber); "
            "call msg.copy() to get a writable one"
        )

    def __delattr__(self, name: str) -> None:
        self.__setattr__(name, None)


def copy(message: Message) -> Any:
    """A deep, writable copy of any message, whatever its field names."""
    cls = message._thawed_class
    values = [_thaw_value(getattr(message, name)) for name in message.__fieldnames__]
    return cls(*values)


# Arrays handed out by in-process loans, by id, each with a weak reference that removes it
# when the array dies (so a recycled id never passes for a loan).
_LOANED: dict[int, weakref.ref[np.ndarray[Any, Any]]] = {}


def loaned_array(length: int, dtype: np.dtype[Any]) -> np.ndarray[Any, Any]:
    """A zeroed array hetros owns, for a loan with no shared-memory slot behind it.

    np.zeros takes lazily zeroed pages, so a large loan costs nothing until it is written.
    """
    array: np.ndarray[Any, Any] = np.zeros(length, dtype)
    key = id(array)

    def forget(_ref: object) -> None:
        _LOANED.pop(key, None)

    _LOANED[key] = weakref.ref(array, forget)
    return array


def _is_loaned(array: np.ndarray[Any, Any]) -> bool:
    ref = _LOANED.get(id(array))
    return ref is not None and ref() is array


def _callers(array: np.ndarray[Any, Any]) -> bool:
    """Whether ``array`` is memory the caller can still write: writable, or a view on writable memory."""
    if _is_loaned(array):
        return False
    if array.flags.writeable:
        return True
    base = array.base
    while isinstance(base, np.ndarray):
        if base.flags.writeable:
            return True
        base = base.base
    return False


class FrozenList(list):  # type: ignore[type-arg]
    """A list field of a read-only message: compares and reads like a list, refuses changes."""

    __slots__ = ()

    def _refuse(self, *_args: object, **_kwargs: object) -> Any:
        raise ReadOnlyMessageError("this list belongs to a message that was handed over (published or "
                                   "delivered); call msg.copy() to get a writable one")

    append = extend = insert = remove = pop = clear = sort = reverse = _refuse
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse


def _seal(message: Message, callers: str) -> Message:
    """Make ``message`` read-only in place: its class, nested messages, lists and arrays.

    ``callers`` says what to do with arrays the caller can still write: ``"freeze"`` them
    (they are hetros' own, e.g. decoded), ``"copy"`` them (in-process readers get the
    very object) or ``"keep"`` them untouched (the transport copies them anyway).
    """
    cls = type(message)
    frozen = cls._frozen_class
    if cls is frozen:
        return message
    for name in cls._array_names:
        value = getattr(message, name)
        if type(value) is not np.ndarray or not (value.flags.writeable or callers != "freeze"):
            continue
        if callers == "freeze" or _is_loaned(value):
            value.flags.writeable = False
        elif callers == "copy" and _callers(value):
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(message, name, value)
    for name in cls._nested_names:
        _seal(getattr(message, name), callers)
    for name in cls._nested_list_names:
        for item in getattr(message, name):
            _seal(item, callers)
    for name in cls._list_names:
        value = getattr(message, name)
        if type(value) is not FrozenList:
            object.__setattr__(message, name, FrozenList(value))
    object.__setattr__(message, "__class__", frozen)
    return message


def hand_over(message: Message, copy_arrays: bool) -> Message:
    """Freeze ``message`` for delivery without taking the caller's arrays.

    An array the caller can still write (writable, or a view on writable memory) is
    replaced by a read-only copy when ``copy_arrays`` (in-process subscribers will hold the
    very object) and left alone otherwise (the transport copies it anyway). Loaned arrays
    and truly read-only ones travel as they are.
    """
    return _seal(message, "copy" if copy_arrays else "keep")


def freeze(message: Message) -> Message:
    """Make ``message`` read-only in place, including nested messages, lists and arrays."""
    return _seal(message, "freeze")


def _thaw_value(value: object) -> object:
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, Message):
        return copy(value)
    if isinstance(value, list):
        return [_thaw_value(v) for v in value]  # a FrozenList thaws into a plain list
    return _copy.copy(value)


def _short_repr(value: object) -> str:
    if isinstance(value, np.ndarray) and value.size > 8:
        return f"array(shape={value.shape}, dtype={value.dtype})"
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."

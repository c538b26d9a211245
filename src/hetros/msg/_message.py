"""The base class of every generated message type.

A message handed to subscribers is *frozen*: its class is swapped for a
read-only twin and its numpy arrays are made non-writeable. Swapping the class
costs nothing at construction time (plain messages keep the fast generated
``__init__``) and makes accidental writes fail loudly instead of silently
changing what another subscriber sees.
"""

from __future__ import annotations

import copy as _copy
import functools
from collections.abc import Callable
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
    _hetros_init: ClassVar[Any]  # the InitSpec its generated __init__ was made of (see _registry)
    # what freeze() must visit, fixed per type when the class is generated
    _array_names: ClassVar[tuple[str, ...]] = ()
    _nested_names: ClassVar[tuple[str, ...]] = ()
    _nested_list_names: ClassVar[tuple[str, ...]] = ()
    _list_names: ClassVar[tuple[str, ...]] = ()

    @staticmethod
    def _hetros_validate(message: Any, where: str = "") -> None:
        """Replaced per type by the registry's generated validator."""

    # replaced per type by a generated sealer on first use (see build_sealer)
    _hetros_seal: ClassVar[Callable[[Message, int], Message]]
    # replaced per type by the compiled copier on first use, where there is one
    _hetros_copy: ClassVar[Callable[[Message], Any]]

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
    return type(message)._hetros_copy(message)


def default_maker(cls: type[Message]) -> Callable[[], Any]:
    """What makes messages as ``cls()`` does, copying one made once: where compiled, a
    third of the cost of the generated constructor (a loan makes one per publish)."""
    template = cls()
    copy(template)  # builds the type's copier, which replaces itself on its first use
    if cls._hetros_copy is _copy_reference:  # no compiled copier: the constructor is faster
        return cls
    return functools.partial(cls._hetros_copy, template)


def _copy_reference(message: Message) -> Any:
    """``copy`` as the generated constructor makes it: the reference the compiled copier stands in for."""
    cls = message._thawed_class
    values = [_thaw_value(getattr(message, name)) for name in message.__fieldnames__]
    return cls(*values)


class LoanBuffer(bytearray):
    """Memory of an in-process loan: an array whose base is one of these is hetros' own."""

    __slots__ = ()


def loaned_array(length: int, dtype: np.dtype[Any]) -> np.ndarray[Any, Any]:
    """A zeroed array hetros owns, for a loan with no shared-memory slot behind it.

    The buffer is zeroed lazily for large sizes (calloc), so a large loan costs nothing
    until it is written; views of it count as loaned too.
    """
    if not length:
        return np.zeros(0, dtype)
    return np.ndarray((length,), dtype, LoanBuffer(length * dtype.itemsize))


def _is_loaned(array: np.ndarray[Any, Any]) -> bool:
    base: Any = array.base
    while type(base) is np.ndarray:
        base = base.base
    return type(base) is LoanBuffer or (type(base) is memoryview and type(base.obj) is LoanBuffer)


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


# What a sealer does with an array the caller can still write (see _seal_array)
_FREEZE, _COPY, _KEEP = 0, 1, 2


def _seal_array(holder: Message, name: str, value: np.ndarray[Any, Any], callers: int) -> None:
    """Seal one array field: ``_FREEZE`` it (hetros' own, e.g. decoded), ``_COPY`` it when the
    caller can still write it (in-process readers get the very object), or ``_KEEP`` it (the
    transport copies it anyway). Loaned arrays are frozen in every mode: they are hetros'."""
    if callers == _FREEZE or _is_loaned(value):
        value.flags.writeable = False
    elif callers == _COPY and _callers(value):
        value = value.copy()
        value.flags.writeable = False
        object.__setattr__(holder, name, value)


def build_sealer(cls: type[Message]) -> Callable[[Message, int], Message]:
    """Straight-line code that seals one ``cls`` message in place.

    Sealing swaps the class for its read-only twin, seals nested messages, turns list fields
    into FrozenLists and makes arrays read-only (per ``callers``, see ``_seal_array``). A
    nested message of its field's own generated class is sealed inline (a call per nested
    message is most of the cost of a small message); any other goes through its sealer.
    """
    namespace: dict[str, Any] = {"_nd": np.ndarray, "_FL": FrozenList,
                                 "_osa": object.__setattr__, "_seal_array": _seal_array}
    lines = ["def seal(m, callers):", "    if type(m) is _F0: return m"]
    namespace["_F0"] = cls._frozen_class
    _seal_body(cls, "m", "    ", lines, namespace, [0])
    lines.append("    return m")
    exec(compile("\n".join(lines), f"<hetros sealer {cls.__msgtype__}>", "exec"), namespace)
    sealer: Callable[[Message, int], Message] = namespace["seal"]
    return sealer


def _seal_body(cls: type[Message], var: str, indent: str, lines: list[str], namespace: dict[str, Any],
               counter: list[int]) -> None:
    """Append the statements that seal ``var`` (known to be exactly ``cls``), nested ones inline."""
    frozen = f"_F{counter[0]}"
    for name in cls._array_names:
        lines += [f"{indent}a = {var}.{name}",
                  f"{indent}if type(a) is _nd and (callers or a.flags.writeable): "
                  f"_seal_array({var}, {name!r}, a, callers)"]
    if cls._nested_names:
        example = cls()
        for name in cls._nested_names:
            counter[0] += 1
            nested, sub = f"v{counter[0]}", type(getattr(example, name))._thawed_class
            namespace[f"_C{counter[0]}"] = sub
            namespace[f"_F{counter[0]}"] = sub._frozen_class
            lines += [f"{indent}{nested} = {var}.{name}", f"{indent}if type({nested}) is _C{counter[0]}:"]
            _seal_body(sub, nested, indent + "    ", lines, namespace, counter)
            lines += [f"{indent}else:", f"{indent}    type({nested})._hetros_seal({nested}, callers)"]
    for name in cls._nested_list_names:
        lines += [f"{indent}for v in {var}.{name}: type(v)._hetros_seal(v, callers)"]
    for name in cls._list_names:
        lines += [f"{indent}v = {var}.{name}", f"{indent}if type(v) is not _FL: _osa({var}, {name!r}, _FL(v))"]
    lines.append(f"{indent}_osa({var}, '__class__', {frozen})")


def _first_seal(message: Message, callers: int) -> Message:
    """Every class starts with this: it builds the class' sealer, installs it and seals."""
    cls = type(message)._thawed_class
    sealer = build_sealer(cls)
    cls._hetros_seal = staticmethod(sealer)
    cls._frozen_class._hetros_seal = staticmethod(sealer)
    return sealer(message, callers)


Message._hetros_seal = staticmethod(_first_seal)
Message._hetros_copy = staticmethod(_copy_reference)


def hand_over(message: Message, copy_arrays: bool) -> Message:
    """Freeze ``message`` for delivery without taking the caller's arrays.

    An array the caller can still write (writable, or a view on writable memory) is
    replaced by a read-only copy when ``copy_arrays`` (in-process subscribers will hold the
    very object) and left alone otherwise (the transport copies it anyway). Loaned arrays
    and truly read-only ones travel as they are.
    """
    return type(message)._hetros_seal(message, _COPY if copy_arrays else _KEEP)


def freeze(message: Message) -> Message:
    """Make ``message`` read-only in place, including nested messages, lists and arrays."""
    return type(message)._hetros_seal(message, _FREEZE)


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

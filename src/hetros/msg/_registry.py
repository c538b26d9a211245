"""The type registry: field definitions, hetros' own message classes, and rosbags' typestore behind them.

The standard ROS 2 definitions and hetros' shipped packages are known from a rendered module
(``_standard_types.py``) without parsing; rosbags' typestore, the slow reference codecs and the
definition renderer, is built on first use (``store``) with every registered type and generated
class, so a worker that only moves messages never pays for it. hetros generates the classes users
construct (with defaults, so ``String()`` works) and registers them in the typestore, so rosbags'
deserializers build hetros classes directly.
"""

from __future__ import annotations

import functools
import keyword
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.serde import SerdeError

from .._errors import DefinitionError, SerializationError, TopicTypeError, UnknownTypeError
from . import _compiled as compiled_codecs
from ._cdr import CdrCodec, Ros1Codec, build_codec, build_ros1_codec
from ._message import FrozenMessage, Message, _copy_reference, build_sealer
from ._standard import PACKAGES as SHIPPED_PACKAGES
from ._standard import load as load_standard_types
from ._validate import NUMPY_DTYPES, Validator, build_validator, convert_array

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

    from ._definitions import FieldUse, PackageDefinitions, ParsedDefinition, Typesdict


SERVICE_EVENT = "_Event"


def _service_event_typedef(service: str) -> tuple[list[Any], list[Any]]:
    """ROS 2's ``<srv>_Event``: what one call looked like at one end (rosidl derives it; so does hetros,
    for the services it knows, on first use)."""
    one = 1  # request and response are sequences of at most one: the event is about one of them
    return [], [("info", (Nodetype.NAME, "service_msgs/msg/ServiceEventInfo")),
                ("request", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{service}_Request"), one))),
                ("response", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{service}_Response"), one)))]


_SCALAR_DEFAULTS = {"bool": "False", "string": "''", "float32": "0.0", "float64": "0.0"}


@dataclass(frozen=True)
class ServiceType:
    """A service type: ``.Request`` and ``.Response`` message classes."""

    name: str
    Request: type[Any]
    Response: type[Any]

    def __repr__(self) -> str:
        return f"<service type {self.name}>"


@dataclass(frozen=True)
class ActionType:
    """An action type with its goal/result/feedback and the types ROS 2 derives."""

    name: str
    Goal: type[Any]
    Result: type[Any]
    Feedback: type[Any]
    SendGoal: ServiceType
    GetResult: ServiceType
    FeedbackMessage: type[Any]

    def __repr__(self) -> str:
        return f"<action type {self.name}>"


# What the node API takes as a service or action type: the registry's instance, or the class the
# typed stubs declare for it (``hetros msg stubs``: Request/Response nested, as rclpy has them)
ServiceKind = ServiceType | type[ServiceType]
ActionKind = ActionType | type[ActionType]


def service_type(kind: ServiceKind) -> ServiceType:
    """The registry's service type behind ``kind`` (the node API's argument)."""
    if isinstance(kind, ServiceType):
        return kind
    raise TopicTypeError(f"service type must be a hetros service type (e.g. "
                         f"hetros.interfaces.std_srvs.srv.SetBool), not {kind!r}")


def action_type(kind: ActionKind) -> ActionType:
    """The registry's action type behind ``kind`` (the node API's argument)."""
    if isinstance(kind, ActionType):
        return kind
    raise TopicTypeError(f"action type must be a hetros action type (e.g. "
                         f"hetros.interfaces.example_interfaces.action.Fibonacci), not {kind!r}")


def normalize_typename(name: str, kind: str = "msg") -> str:
    """Accept ``pkg/Name``, ``pkg/msg/Name`` and ``pkg.msg.Name``; return ``pkg/kind/Name``."""
    parts = name.replace(".", "/").replace("::", "/").split("/")
    if len(parts) == 2:
        return f"{parts[0]}/{kind}/{parts[1]}"
    if len(parts) == 3:
        return "/".join(parts)
    raise UnknownTypeError(
        f"type name must look like 'pkg/{kind}/Name' or 'pkg/Name', not {name!r}"
    )


class TypeRegistry:
    """All message, service and action types known to one process."""

    def __init__(self, compiled: bool | None = None) -> None:
        """``compiled``: codecs and validators from the compiled interpreter (default: when it is
        built and ``HETROS_PURE_PYTHON`` is not set), else the generated Python ones."""
        self.compiled = compiled_codecs.available() if compiled is None else compiled and compiled_codecs.available()
        self._lock = threading.RLock()
        standard = load_standard_types()
        self.fielddefs: Typesdict = {**standard.standard, **standard.shipped}
        self._store: Typestore | None = None
        # registered after rosbags' own types when the store is built: the shipped and loaded packages' types
        self._registered: list[Typesdict] = [dict(standard.shipped)]
        self._classes: dict[str, type[Message]] = {}
        self._codecs: dict[str, CdrCodec] = {}
        self._ros1_codecs: dict[str, Ros1Codec | None] = {}
        self.services: dict[str, ServiceType] = {}
        self.actions: dict[str, ActionType] = {}
        self.sources: dict[str, str] = dict.fromkeys(standard.standard, "rosbags ROS 2 jazzy store")
        self._loaded_folders: set[Path] = set()
        self._defaults: dict[str, dict[str, Any]] = {name: dict(d) for name, d in standard.shipped_defaults.items()}
        for name, where in standard.shipped_sources.items():
            self.sources[name] = str(SHIPPED_PACKAGES / where)
        self._loaded_folders.update(package.resolve() for package in SHIPPED_PACKAGES.iterdir() if package.is_dir())
        self._register_interfaces(standard.shipped_services, standard.shipped_actions)

    @property
    def store(self) -> Typestore:
        """rosbags' typestore with every registered type and generated class (built on first use: the
        reference codecs, ROS 1 mapping and definition rendering need it, moving messages does not)."""
        store = self._store
        if store is None:
            with self._lock:
                store = self._store
                if store is None:
                    from rosbags.typesys import Stores, TypesysError, get_typestore

                    store = get_typestore(Stores.ROS2_JAZZY)
                    store.types = dict(store.types)
                    store.fielddefs = dict(store.fielddefs)
                    for typedefs in self._registered:
                        try:
                            store.register(typedefs)
                        except TypesysError as exc:
                            raise DefinitionError(", ".join(sorted(typedefs)), 0, str(exc)) from exc
                    store.types.update(self._classes)
                    self._store = store
        return store

    # -- loading ---------------------------------------------------------------------------

    def load_folder(self, folder: Path) -> list[str]:
        """Load one package folder, or every package folder inside ``folder``."""
        from ._definitions import find_packages, read_package  # the parser: only where a project brings packages

        loaded: list[str] = []
        for package in find_packages(Path(folder)):
            resolved = package.resolve()
            if resolved in self._loaded_folders:
                continue
            self._register_package(read_package(package))
            self._loaded_folders.add(resolved)
            loaded.append(package.name)
        return loaded

    def _register_package(self, pkg: PackageDefinitions) -> None:
        with self._lock:
            typedefs: Typesdict = {}
            uses: list[FieldUse] = []
            for parsed in pkg.messages:
                typedefs.update(parsed.typedefs)
                uses.extend(parsed.uses)
                if parsed.uses:
                    self.sources[parsed.name] = parsed.uses[0].path
            known = set(self.fielddefs) | set(typedefs)
            _refuse_recursion(pkg.messages)
            for use in uses:
                if use.typename not in known:
                    raise DefinitionError(
                        use.path,
                        use.line,
                        f"unknown field type {use.typename!r}: define it in a loaded package "
                        "or fix the name (e.g. 'std_msgs/Header', 'geometry_msgs/Point')",
                    )
            self._add_definitions(pkg.package, typedefs)
            for parsed in pkg.messages:
                if parsed.defaults:
                    self._defaults[parsed.name] = dict(parsed.defaults)
            self._register_interfaces(pkg.services, pkg.actions)

    def _add_definitions(self, where: str, typedefs: Typesdict) -> None:
        """rosbags' rule for a type registered twice: the same fields (names compared without case), or
        an error naming the type."""
        for name, (_, fields) in typedefs.items():
            have = self.fielddefs.get(name)
            if have is not None and [(f[0].lower(), f[1]) for f in have[1]] != [(f[0].lower(), f[1]) for f in fields]:
                raise DefinitionError(where, 0, f"Type {name!r} is already present with different definition.")
        self._registered.append(typedefs)
        for name in typedefs.keys() - self.fielddefs.keys():
            self.fielddefs[name] = typedefs[name]
        if self._store is not None:
            from rosbags.typesys import TypesysError

            try:
                self._store.register(typedefs)
            except TypesysError as exc:
                raise DefinitionError(where, 0, str(exc)) from exc

    def _register_interfaces(self, services: tuple[str, ...], actions: tuple[str, ...]) -> None:
        for service in services:
            self.services[service] = ServiceType(
                service, self.get(f"{service}_Request"), self.get(f"{service}_Response")
            )
        for action in actions:
            send_goal, get_result = (
                ServiceType(f"{action}_{part}", self.get(f"{action}_{part}_Request"),
                            self.get(f"{action}_{part}_Response"))
                for part in ("SendGoal", "GetResult")
            )
            # an action's endpoints are services and topics (``hetros.plan.action_endpoints``)
            self.services[send_goal.name] = send_goal
            self.services[get_result.name] = get_result
            self.actions[action] = ActionType(
                action,
                self.get(f"{action}_Goal"),
                self.get(f"{action}_Result"),
                self.get(f"{action}_Feedback"),
                send_goal,
                get_result,
                self.get(f"{action}_FeedbackMessage"),
            )

    # -- lookup ----------------------------------------------------------------------------

    def has(self, name: str) -> bool:
        try:
            return normalize_typename(name) in self.fielddefs
        except UnknownTypeError:
            return False

    def get(self, name: str) -> type[Any]:
        """The message class for ``name``; generated on first use."""
        full = normalize_typename(name)
        cls = self._classes.get(full)
        if cls is not None:
            return cls
        with self._lock:
            base = full.removesuffix(SERVICE_EVENT)
            if full not in self.fielddefs and base != full and base in self.services:
                self._add_definitions("service events", {full: _service_event_typedef(base)})
            if full not in self.fielddefs:
                raise UnknownTypeError(
                    f"unknown message type {name!r}: add the package folder that defines it to "
                    "'messages:' in the project file (see `hetros msg show` for known types)"
                )
            return self._generate(full)

    def service_event(self, service_type: str) -> type[Any]:
        """The ``<srv>_Event`` message ROS 2 derives from a service for its introspection
        (``<service>/_service_event``: ServiceEventInfo, and the request or response it is about)."""
        return self.get(f"{self.get_service(service_type).name}{SERVICE_EVENT}")

    def get_service(self, name: str) -> ServiceType:
        full = normalize_typename(name, "srv")
        if full not in self.services:
            raise UnknownTypeError(
                f"unknown service type {name!r}: ship its .srv in a package listed under 'messages:'"
            )
        return self.services[full]

    def get_action(self, name: str) -> ActionType:
        full = normalize_typename(name, "action")
        if full not in self.actions:
            raise UnknownTypeError(
                f"unknown action type {name!r}: ship its .action in a package listed under 'messages:'"
            )
        return self.actions[full]

    def codec(self, name: str) -> CdrCodec:
        """The generated CDR codec of a message type (built on first use, then shared)."""
        full = normalize_typename(name)
        codec = self._codecs.get(full)
        if codec is None:
            self.get(full)
            with self._lock:
                codec = self._codecs.get(full)
                if codec is None:
                    codec = self._codecs[full] = build_codec(self, full)
        return codec

    def ros1_codec(self, name: str) -> Ros1Codec | None:
        """The generated ROS 1 codec of a type whose ROS 1 definition is its own; None where the
        generator has no code for it (the caller keeps rosbags' ROS 1 serializer)."""
        full = normalize_typename(name)
        if full not in self._ros1_codecs:
            self.get(full)
            with self._lock:
                if full not in self._ros1_codecs:
                    self._ros1_codecs[full] = build_ros1_codec(self, full)
        return self._ros1_codecs[full]

    def names(self) -> list[str]:
        return sorted(self.fielddefs)

    # -- codecs ----------------------------------------------------------------------------

    def serialize(self, message: Message) -> memoryview:
        """CDR (little endian, with encapsulation header) as ROS 2 puts on the wire."""
        try:
            return self.store.serialize_cdr(message, message.__msgtype__)
        except (SerdeError, AttributeError, TypeError, ValueError, OverflowError) as exc:
            raise SerializationError(f"cannot serialize {message.__msgtype__}: {exc}") from exc

    def deserialize(self, data: bytes | memoryview, typename: str) -> Message:
        store = self.store
        from rosbags.typesys import TypesysError

        try:
            message = store.deserialize_cdr(data, typename)
        except (SerdeError, IndexError, ValueError, TypesysError) as exc:
            raise SerializationError(
                f"{len(data)} bytes do not decode as {typename}: {exc}"
            ) from exc
        assert isinstance(message, Message)
        return message

    def definition_text(self, name: str) -> str:
        """The full definition with nested types, as `hetros msg show` prints it."""
        full = normalize_typename(name)
        self.get(full)
        store = self.store
        from rosbags.typesys import TypesysError

        try:
            text, _ = store.generate_msgdef(full, ros_version=2)
        except (AssertionError, TypesysError, KeyError):
            # rosbags renders only msg/ types nested; service and action parts are listed here
            return self._render(full)
        return str(text)

    def _render(self, full: str) -> str:
        """The definition of ``full`` and every type it nests, one block each, ROS style."""
        blocks: list[str] = []
        pending, seen = [full], {full}
        while pending:
            name = pending.pop(0)
            consts, fields = self.fielddefs[name]
            lines = [f"{ctype} {cname}={cvalue}" for cname, ctype, cvalue in consts]
            for fname, desc in fields:
                text, nested = _field_type(desc)
                lines.append(f"{text} {fname}")
                for sub in nested:
                    if sub not in seen:
                        seen.add(sub)
                        pending.append(sub)
            header = "" if name == full else "=" * 80 + f"\nMSG: {name}\n"
            blocks.append(header + "\n".join(lines))
        return "\n".join(blocks) + "\n"

    # -- class generation ------------------------------------------------------------------

    def _generate(self, full: str) -> type[Message]:
        if full in self._classes:
            return self._classes[full]
        consts, fields = self.fielddefs[full]
        # Generated code names its helpers with a leading underscore: rosidl field names cannot
        # start with one, so no field (``self``, ``np``, ``copy``...) shadows them.
        namespace: dict[str, Any] = {"_np": np, "_Message": Message, "_FrozenMessage": FrozenMessage,
                                     "_U": _UNSET, "_L": _as_list}
        defaults = self._defaults.get(full, {})
        inits: list[InitField] = []
        for index, (name, desc) in enumerate(fields):
            attr = _attr_name(name)
            default_expr, coerce = self._default_for(desc, namespace, index, defaults.get(name, _NO_DEFAULT),
                                                     f"{full.rsplit('/', 1)[-1]}.{attr}")
            inits.append(InitField(attr, default_expr, f"{coerce}({attr})" if coerce else attr))
        fieldnames = [field.attr for field in inits]
        short = full.rsplit("/", 1)[-1]
        lines = [f"class {short}(_Message):", f"    __slots__ = {tuple(fieldnames)!r}"]
        lines.append(f"    __msgtype__ = {full!r}")
        lines.append(f"    __fieldnames__ = {tuple(fieldnames)!r}")
        for cname, _ctype, cvalue in consts:
            lines.append(f"    {cname} = {cvalue!r}")
        lines.extend(f"    {line}" for line in init_source(inits, {}))
        lines.append(f"class Frozen{short}(_FrozenMessage, {short}):")
        lines.append("    __slots__ = ()")
        try:
            exec(compile("\n".join(lines), f"<hetros message {full}>", "exec"), namespace)
        except SyntaxError as exc:  # names the definition checks let through would land here
            raise DefinitionError(self.sources.get(full, full), 0,
                                  f"cannot generate a class for {full}: {exc.msg}") from exc
        cls: type[Message] = namespace[short]
        frozen: type[Message] = namespace[f"Frozen{short}"]
        package, kind, _ = full.split("/")
        cls.__module__ = frozen.__module__ = f"hetros.interfaces.{package}.{kind}"
        cls.__qualname__ = short
        cls._frozen_class = frozen
        cls._thawed_class = cls
        cls._hetros_init = InitSpec(tuple(inits), namespace)
        kinds = [(attr, desc) for attr, (_name, desc) in zip(fieldnames, fields, strict=True)]
        cls._array_names = tuple(a for a, d in kinds if d[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE)
                                 and d[1][0][0] == Nodetype.BASE and d[1][0][1][0] != "string")
        cls._nested_names = tuple(a for a, d in kinds if d[0] == Nodetype.NAME)
        cls._nested_list_names = tuple(a for a, d in kinds if d[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE)
                                       and d[1][0][0] == Nodetype.NAME)
        cls._list_names = tuple(a for a, d in kinds if d[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE)
                                and a not in cls._array_names)
        setattr(cls, "_hetros_validate", staticmethod(self._lazy_validator(full, cls)))  # noqa: B010
        if self.compiled:  # else the class keeps Message's generated sealer, built on first use, and copier
            cls._hetros_seal = frozen._hetros_seal = staticmethod(self._lazy_sealer(full, cls))
            cls._hetros_copy = frozen._hetros_copy = staticmethod(self._lazy_copier(full, cls))
        self._classes[full] = cls
        if self._store is not None:
            self._store.types[full] = cls
            self._store.cache.pop(full, None)
        return cls

    def _lazy_sealer(self, full: str, cls: type[Message]) -> Callable[[Message, int], Message]:
        """Builds the type's compiled sealer on its first use."""

        def first_use(message: Message, callers: int) -> Message:
            sealer = compiled_codecs.compile_sealer(self, full, build_sealer(cls))
            cls._hetros_seal = cls._frozen_class._hetros_seal = staticmethod(sealer)
            return sealer(message, callers)

        return first_use

    def _lazy_copier(self, full: str, cls: type[Message]) -> Callable[[Message], Any]:
        """Builds the type's compiled copier on its first use."""

        def first_use(message: Message) -> Any:
            copier = compiled_codecs.compile_copier(self, full, _copy_reference)
            cls._hetros_copy = cls._frozen_class._hetros_copy = staticmethod(copier)
            return copier(message)

        return first_use

    def _lazy_validator(self, full: str, cls: type[Message]) -> Validator:
        """Builds the type's validator on its first use (most types are never published)."""

        def first_use(message: Any, where: str = "") -> None:
            validator = build_validator(self, full)
            if self.compiled:
                validator = compiled_codecs.compile_validator(self, full, validator)
            setattr(cls, "_hetros_validate", staticmethod(validator))  # noqa: B010 (a method mypy sees as fixed)
            validator(message, where or full.rsplit("/", 1)[-1])

        return first_use

    def _default_for(self, desc: Any, namespace: dict[str, Any], index: int,
                     declared: Any = None, where: str = "") -> tuple[str, str]:
        """A Python expression for the default value, and a coercion function name (or '')."""
        kind, arg = desc
        has_declared = declared is not _NO_DEFAULT
        if has_declared:
            namespace[f"_d{index}"] = declared
        if kind == Nodetype.BASE:
            if has_declared:
                return f"_d{index}", ""
            return _SCALAR_DEFAULTS.get(arg[0], "0"), ""
        if kind == Nodetype.NAME:
            sub = self._generate(arg)
            namespace[f"_T{index}"] = sub
            return f"_T{index}()", ""
        subdesc, length = arg
        if subdesc[0] == Nodetype.BASE and subdesc[1][0] != "string":
            dtype = np.dtype(NUMPY_DTYPES[subdesc[1][0]])
            namespace[f"_dt{index}"] = dtype
            namespace[f"_co{index}"] = functools.partial(
                convert_array, dtype=dtype, where=f"{where}", length=length if kind == Nodetype.ARRAY else 0,
                bounded=False)
            if has_declared:
                return f"_np.array(_d{index}, _dt{index})", f"_co{index}"
            size = length if kind == Nodetype.ARRAY else 0
            return f"_np.zeros({size}, _dt{index})", f"_co{index}"
        if subdesc[0] == Nodetype.BASE:
            if has_declared:
                return f"list(_d{index})", "_L"
            return (f"[''] * {length}" if kind == Nodetype.ARRAY else "[]"), "_L"
        sub = self._generate(subdesc[1])
        namespace[f"_T{index}"] = sub
        if kind == Nodetype.ARRAY:
            return f"[_T{index}() for _ in range({length})]", "_L"
        return "[]", "_L"


_NO_DEFAULT: Any = object()


@dataclass(frozen=True)
class InitField:
    """One field as a generated constructor fills it: ``default`` when the argument is not given (or None,
    as in rospy's generated classes: ``Point(1.0, None, 2.0)``), else ``value`` (the argument, coerced)."""

    attr: str
    default: str
    value: str


@dataclass(frozen=True)
class InitSpec:
    """What a message class's generated ``__init__`` was made of, kept so that a subclass that stores
    some fields differently (rclpy's flavour) gets a constructor as flat as its base's."""

    fields: tuple[InitField, ...]
    namespace: dict[str, Any]


def init_source(fields: Sequence[InitField], stores: Mapping[str, str]) -> list[str]:
    """The lines of a generated ``__init__`` over ``fields``; ``stores[attr]``, a format with ``{default}``
    and ``{value}``, replaces the plain assignment of that field."""
    params = ", ".join(f"{field.attr}=_U" for field in fields)
    lines = [f"def __init__(_m, {params}):" if params else "def __init__(_m):"]
    for field in fields:
        if field.attr in stores:
            stored = stores[field.attr].format(default=field.default, value=field.value)
            lines.append(f"    {stored}")
        else:
            lines.append(f"    _m.{field.attr} = {field.default} if {field.attr} is _U or {field.attr} is None "
                         f"else {field.value}")
    lines.append("    _m._hetros_loan = None")  # set, so the transport's check for a loan is cheap
    return lines


def _as_list(value: Any) -> Any:
    """A list field keeps its own list; anything else stays as given for the validator to name."""
    return list(value) if isinstance(value, (list, tuple)) else value
# "not given" for generated constructors: an explicit None is stored, and refused when published
_UNSET: Any = type("Unset", (), {"__repr__": lambda self: "<default>"})()


def _field_type(desc: Any) -> tuple[str, list[str]]:
    """A field's type as a definition writes it, and the message types it nests."""
    kind, arg = desc
    if kind == Nodetype.BASE:
        base, bound = arg
        return (f"{base}<={bound}" if bound else base), []
    if kind == Nodetype.NAME:
        return str(arg), [str(arg)]
    inner, nested = _field_type(arg[0])
    length = arg[1]
    if kind == Nodetype.ARRAY:
        return f"{inner}[{length}]", nested
    return (f"{inner}[<={length}]" if length else f"{inner}[]"), nested


def _refuse_recursion(definitions: tuple[ParsedDefinition, ...]) -> None:
    """A message that contains itself (directly, through others, or in a sequence) has no size.

    Depth-first over the package's own types (loaded types cannot refer back to new ones),
    iterative so that a long chain of types costs no Python recursion.
    """
    uses = {d.name: d.uses for d in definitions}
    finished: set[str] = set()
    for root in uses:
        if root in finished:
            continue
        path = [root]
        pending = [iter(uses[root])]
        while pending:
            use = next(pending[-1], None)
            if use is None:
                finished.add(path.pop())
                pending.pop()
                continue
            target = use.typename
            if target in path:
                cycle = " -> ".join([*path[path.index(target):], target])
                raise DefinitionError(use.path, use.line, f"field {use.field!r} makes {target} contain "
                                      f"itself ({cycle}); a ROS message cannot be recursive")
            if target in uses and target not in finished:
                path.append(target)
                pending.append(iter(uses[target]))


def _attr_name(name: str) -> str:
    return name + "_" if keyword.iskeyword(name) and not name.endswith("_") else name


_registry: TypeRegistry | None = None
_registry_lock = threading.Lock()


def registry() -> TypeRegistry:
    """The process-wide registry (created on first use)."""
    global _registry
    if _registry is None:
        with _registry_lock:
            if _registry is None:
                _registry = TypeRegistry()
    return _registry

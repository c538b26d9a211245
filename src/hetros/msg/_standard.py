"""The definitions every process knows before it parses anything, rendered once into ``standard_types.json``.

ROS 2 Jazzy's standard types come from rosbags' store and the packages hetros ships (``msg/packages``)
from their .msg/.srv/.action files. Reading either at run time costs a worker about 7 MB: rosbags' type
system builds a dataclass per standard type and maps OpenSSL for its hashes (and the same definitions as a
Python literal cost 3.6 MB of constants, JSON 0.5 MB). The rendered file holds the field definitions as
JSON; rosbags' store is built only when something asks for it (``TypeRegistry.store``).
``tests/unit/test_standard_types.py`` renders again and compares, so the file cannot go stale: regenerate
it with ``python -m hetros.msg._standard``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosbags.interfaces import Nodetype

TARGET = Path(__file__).with_name("standard_types.json")
PACKAGES = Path(__file__).with_name("packages")
_NOTICE = "DO NOT EDIT: rendered by `python -m hetros.msg._standard`; tests/unit/test_standard_types.py checks it"


@dataclass(frozen=True)
class StandardTypes:
    """What ``standard_types.json`` holds, in rosbags' field-definition form."""

    standard: dict[str, Any]
    shipped: dict[str, Any]
    shipped_sources: dict[str, str]  # relative to msg/packages
    shipped_defaults: dict[str, dict[str, Any]]
    shipped_services: tuple[str, ...]
    shipped_actions: tuple[str, ...]


def _desc(raw: list[Any]) -> tuple[Any, Any]:
    kind = Nodetype(raw[0])
    if kind == Nodetype.BASE:
        return kind, tuple(raw[1])
    if kind == Nodetype.NAME:
        return kind, raw[1]
    return kind, (_desc(raw[1][0]), raw[1][1])


def _definitions(raw: dict[str, Any]) -> dict[str, Any]:
    return {name: ([tuple(const) for const in consts], [(field, _desc(desc)) for field, desc in fields])
            for name, (consts, fields) in raw.items()}


def load() -> StandardTypes:
    raw = json.loads(TARGET.read_text(encoding="utf-8"))
    return StandardTypes(_definitions(raw["standard"]), _definitions(raw["shipped"]), raw["shipped_sources"],
                         raw["shipped_defaults"], tuple(raw["shipped_services"]), tuple(raw["shipped_actions"]))


def _plain(value: Any) -> Any:
    if isinstance(value, Nodetype):
        return int(value)
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    return value


def render() -> str:
    from rosbags.typesys import Stores, get_typestore

    from ._definitions import find_packages, read_package

    standard = get_typestore(Stores.ROS2_JAZZY).fielddefs
    shipped: dict[str, Any] = {}
    defaults: dict[str, dict[str, Any]] = {}
    sources: dict[str, str] = {}
    services: list[str] = []
    actions: list[str] = []
    for package in find_packages(PACKAGES):
        definitions = read_package(package)
        for parsed in definitions.messages:
            shipped.update(parsed.typedefs)
            if parsed.defaults:
                defaults[parsed.name] = dict(parsed.defaults)
            if parsed.uses:
                sources[parsed.name] = Path(parsed.uses[0].path).relative_to(PACKAGES).as_posix()
        services += definitions.services
        actions += definitions.actions

    def table(key: str, rows: dict[str, Any]) -> list[str]:
        body = [f"  {json.dumps(name)}: {json.dumps(_plain(rows[name]))}" for name in sorted(rows)]
        return [f'"{key}": {{', ",\n".join(body), "},"] if body else [f'"{key}": {{}},']

    lines = ["{", f'"//": {json.dumps(_NOTICE)},', *table("standard", dict(standard)), *table("shipped", shipped),
             *table("shipped_sources", sources), *table("shipped_defaults", defaults),
             f'"shipped_services": {json.dumps(services)},', f'"shipped_actions": {json.dumps(actions)}', "}", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    TARGET.write_text(render(), encoding="utf-8")

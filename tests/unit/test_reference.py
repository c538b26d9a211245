"""The project file's reference is generated from the model and cannot drift from it."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from hetros import ProjectError
from hetros._qos import QoS
from hetros.project import load_project
from hetros.project._model import ExternalSpec, HostSpec, NodeSpec, Project, Ros1Spec, Ros2Spec, TargetSpec
from hetros.project._reference import known_keys, reference_markdown

DOCS = Path(__file__).resolve().parents[2] / "docs" / "PROJECT_FILE.md"


def test_the_committed_reference_is_the_generated_one() -> None:
    assert DOCS.read_text(encoding="utf-8") == reference_markdown(), \
        "docs/PROJECT_FILE.md is stale: run `hetros reference > docs/PROJECT_FILE.md`"


def test_every_key_of_the_model_is_documented_with_a_meaning() -> None:
    text = reference_markdown()
    keys = [info.alias or name for model in (Project, TargetSpec, NodeSpec, HostSpec, ExternalSpec, Ros1Spec, Ros2Spec)
            for name, info in model.model_fields.items()]
    keys += [field.name for field in dataclasses.fields(QoS)]
    for key in keys:
        row = next((line for line in text.splitlines() if line.startswith(f"| `{key}` |")), None)
        assert row is not None, f"{key} is not in the reference"
        assert not row.rstrip().endswith("|  |"), f"{key} has no meaning in the reference: {row}"


@pytest.mark.parametrize(("yaml_path", "expected"), [
    ((), "hosts"), (("nodes", "a"), "subscribe"), (("targets", "t"), "cpus"), (("topics", "/x"), "depth"),
    (("external", "ros2"), "peers"), (("nodes", "a", "publish", "/x"), "deadline"),
])
def test_known_keys_follow_the_yaml_path(yaml_path: tuple[str, ...], expected: str) -> None:
    assert expected in known_keys(yaml_path)


@pytest.mark.parametrize(("text", "message"), [
    ("topics: {/x: {dpeth: 3}}", "topics./x.dpeth: unknown key 'dpeth'; did you mean 'depth'?"),
    ("targets: {t: {kind: process, cpu: [0]}}", "targets.t.cpu: unknown key 'cpu'; did you mean 'cpus'?"),
    ("on_peer_lsot: stop", "on_peer_lsot: unknown key 'on_peer_lsot'; did you mean 'on_peer_lost'?"),
    ("zzz: 1", "unknown key 'zzz': one of args, chains, dds_domain, external, foxglove_hosts, groups, hosts, include, "
               "messages, name, nodes"),
])
def test_a_mistyped_key_gets_the_nearest_one(tmp_path: Path, text: str, message: str) -> None:
    project = tmp_path / "p.yaml"
    project.write_text("name: p\nnodes: {a: {run: m:f, target: t}}\n"
                       + ("targets: {t: {kind: thread}}\n" if "targets" not in text else "") + text + "\n")
    with pytest.raises(ProjectError) as info:
        load_project(project)
    assert message in str(info.value)

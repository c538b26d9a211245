"""fpgaDDS's lane-following vehicle over two hosts (examples/lane_following/project_hosts.yaml):
the same results as on one host, with the image chain crossing between them over DDS."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tests.support.netns import Namespace, unavailable

pytestmark = pytest.mark.skipif(bool(unavailable()), reason=f"no network namespaces here: {unavailable()}")

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "lane_following"


def test_the_vehicle_over_two_hosts_gives_the_one_host_results(spaces: list[Namespace], tmp_path: Path) -> None:
    data = yaml.safe_load((EXAMPLE / "project_hosts.yaml").read_text())
    data["messages"] = [str((EXAMPLE / m).resolve()) for m in data["messages"]]
    data["hosts"]["vehicle"]["address"] = spaces[0].address
    data["hosts"]["pc"]["address"] = spaces[1].address
    data["nodes"]["camera"]["parameters"]["frames"] = 45
    data["nodes"]["monitor"]["parameters"].update({"frames": 45, "out": str(tmp_path / "out")})
    project = tmp_path / "project_hosts.yaml"
    project.write_text(yaml.safe_dump(data, sort_keys=False))
    env_path = f"PYTHONPATH={EXAMPLE}"
    runs = {host: subprocess.Popen(space.command("env", env_path, sys.executable, "-m", "hetros", "launch",
                                                 str(project), "--duration", "150"),
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
            for host, space in (("vehicle", spaces[0]), ("pc", spaces[1]))}
    outputs = {host: run.communicate(timeout=200)[0] for host, run in runs.items()}
    vehicle = outputs["vehicle"]
    assert runs["vehicle"].returncode == 0, vehicle
    found = re.search(r"centre error max ([\d.]+) px; stopped in frames \[([\d, ]*)\]", vehicle)
    assert found, vehicle
    assert float(found.group(1)) < 3.0
    assert [int(f) for f in found.group(2).split(", ") if f] == list(range(20, 35))
    assert re.search(r"dds: sent (\d+) samples of /image_comp to other hosts", vehicle), vehicle
    received = re.search(r"dds: received (\d+) samples of /cmd_vel from pc", vehicle)
    assert received and int(received.group(1)) == 45, vehicle
    # the vehicle ended in order: the pc ends in order too, not with a lost host
    assert re.search(r"host vehicle \(\S+\) finished", outputs["pc"]), outputs["pc"]
    assert "is gone" not in outputs["pc"], outputs["pc"]
    assert runs["pc"].returncode == 0, outputs["pc"]
    for host, output in outputs.items():
        assert "Traceback" not in output and "Exception in thread" not in output, f"{host}:\n{output}"

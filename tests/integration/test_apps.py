"""Reference applications from the papers, each in both mappings, results checked."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def launch(project: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "120"],
                          capture_output=True, text=True, timeout=180, check=False)


def load(example: str) -> object:
    spec = importlib.util.spec_from_file_location(f"{example}_nodes", EXAMPLES / example / "nodes.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_ping_pong_round_trips_every_size_intact(project: str) -> None:
    result = launch(EXAMPLES / "ping_pong" / project)
    assert result.returncode == 0, result.stderr
    sizes = [int(s) for s in re.findall(r"\[ping\]: round trip +(\d+) B:", result.stderr)]
    assert sizes == [4, 8192, 1 << 20, 6 << 20]
    assert "required node ping finished" in result.stderr


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_sorting_matches_numpy_in_both_mappings(project: str) -> None:
    result = launch(EXAMPLES / "sorting" / project)
    assert result.returncode == 0, result.stderr
    assert len(re.findall(r"run \d: 2048 numbers sorted correctly", result.stderr)) == 5


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_sort_action_matches_numpy_in_both_mappings_and_styles(project: str) -> None:
    """Processes with a callback server; threads with ReconROS's take-goal server."""
    result = launch(EXAMPLES / "sort_action" / project)
    assert result.returncode == 0, result.stderr
    assert len(re.findall(r"run \d: 2048 numbers sorted correctly, 8 feedback messages in order",
                          result.stderr)) == 3


@pytest.mark.parametrize("size", [0, 1, 2, 3, 17, 2048])
def test_odd_even_transposition_sort(size: int) -> None:
    sort = load("sorting").odd_even_transposition_sort  # type: ignore[attr-defined]
    values = np.random.default_rng(size).integers(0, 2**32, size, dtype=np.uint32)
    assert np.array_equal(sort(values), np.sort(values))
    assert np.array_equal(sort(np.sort(values)[::-1]), np.sort(values))


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_sobel_service_pipeline(project: str) -> None:
    result = launch(EXAMPLES / "sobel" / project)
    assert result.returncode == 0, result.stderr
    frames = sorted(int(n) for n in re.findall(r"\[display\]: frame (\d+) filtered correctly", result.stderr))
    assert frames == list(range(10)), "every frame reached the display, filtered as the reference says"


def test_sobel_matches_scipy_reference() -> None:
    ndimage = pytest.importorskip("scipy.ndimage")
    nodes = load_with_types("sobel")
    img = nodes.frame(3)  # type: ignore[attr-defined]
    ours = nodes.sobel(img)  # type: ignore[attr-defined]
    for channel in range(3):
        plane = img[..., channel].astype(np.int32)
        reference = np.abs(ndimage.sobel(plane, axis=1)) + np.abs(ndimage.sobel(plane, axis=0))
        expected = np.clip(reference, 0, 255)[1:-1, 1:-1]
        assert np.array_equal(ours[1:-1, 1:-1, channel], expected)
    assert not ours[0].any() and not ours[:, -1].any()


def load_with_types(example: str) -> object:
    from hetros.msg import registry

    registry().load_folder(EXAMPLES / example / "msg")
    return load(example)


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_inverse_kinematics_against_a_numeric_solution(project: str) -> None:
    optimize = pytest.importorskip("scipy.optimize")
    sys.path.insert(0, str(EXAMPLES / "inverse_kinematics"))
    try:
        import kinematics  # type: ignore[import-not-found]
    finally:
        sys.path.pop(0)
    result = launch(EXAMPLES / "inverse_kinematics" / project)
    assert result.returncode == 0, result.stderr
    answers = re.findall(r"command (0x[0-9a-f]+) -> pwm ((?:\d+ ?){6})", result.stderr)
    assert len(answers) == 20
    for command, pwm in answers:
        x, y = kinematics.unpack(int(command, 16))
        joints = kinematics.platform_joints(x, y)
        for leg in range(6):
            beta = kinematics.BETA[leg]

            def rod_error(alpha: float, leg: int = leg, beta: float = beta, joints: np.ndarray = joints) -> float:
                tip = kinematics.BASE[leg] + kinematics.ARM * np.array(
                    [np.cos(alpha) * np.cos(beta), np.cos(alpha) * np.sin(beta), np.sin(alpha)])
                return float(np.linalg.norm(joints[leg] - tip) - kinematics.ROD)

            alpha = optimize.brentq(rod_error, -np.pi / 2, np.pi / 2)
            expected = round((np.degrees(alpha) + 90.0) / 180.0 * 1023.0)
            assert abs(int(pwm.split()[leg]) - expected) <= 1, (command, leg)


def variant(tmp_path: Path, name: str, mapping: str, node: str, **parameters: object
            ) -> subprocess.CompletedProcess[str]:
    """A shipped project with other parameters for one node (e.g. a faster tick in simulated time)."""
    import os

    import yaml

    example = EXAMPLES / name
    data = yaml.safe_load((example / mapping).read_text())
    data["messages"] = [str((example / m).resolve()) for m in data["messages"]]
    data["nodes"][node].setdefault("parameters", {}).update(parameters)
    project = tmp_path / f"{node}-{'-'.join(map(str, parameters.values()))}-{mapping}"
    project.write_text(yaml.safe_dump(data))
    env = dict(os.environ, PYTHONPATH=str(example))
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "120"],
                          capture_output=True, text=True, timeout=180, check=False, env=env)


def ball_on_plate(tmp_path: Path, mapping: str, seed: int) -> subprocess.CompletedProcess[str]:
    return variant(tmp_path, "ball_on_plate", mapping, "physics", seed=seed, hz=200.0)


def test_three_ball_on_plate_stations_from_one_definition_settle() -> None:
    """project_stations.yaml includes the station three times under namespaces, each with its own starting
    ball (seeds 1, 2, 3): three independent control loops over one set of node code."""
    result = subprocess.run([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "ball_on_plate" /
                                                                              "project_stations.yaml"),
                             "--duration", "14"], capture_output=True, text=True, timeout=180, check=False)
    assert result.returncode == 0, result.stderr
    outcomes = {}
    for station in ("station1", "station2", "station3"):
        found = re.search(rf"\[{station}_physics\]: after 10\.0 s: ball at \S+ \S+ m, ([\d.]+) m from the "
                          r"centre; farthest ([\d.]+) m; settled at ([\d.]+) s", result.stderr)
        assert found, result.stderr
        distance, farthest, settled = (float(v) for v in found.groups())
        assert distance < 0.01 and farthest < 0.10 and settled < 10.0
        assert re.search(rf"\[{station}_control\]: control period [\d.]+ ± [\d.]+ ms", result.stderr)
        outcomes[station] = found.group(0).split(":", 1)[1]
    assert len(set(outcomes.values())) == 3, "each station started from its own ball"


def test_ball_on_plate_mappings_agree(tmp_path: Path) -> None:
    outcomes = []
    for mapping in ("project.yaml", "project_threads.yaml"):
        result = ball_on_plate(tmp_path, mapping, 2)
        assert result.returncode == 0, result.stderr
        outcomes.append(re.search(r"\[physics\]: after .*", result.stderr).group(0))  # type: ignore[union-attr]
    assert outcomes[0] == outcomes[1]


def test_autoware_slice_follows_the_route_in_both_mappings(tmp_path: Path) -> None:
    summaries = []
    for mapping in ("project.yaml", "project_threads.yaml"):
        result = variant(tmp_path, "autoware", mapping, "vehicle", hz=100.0)
        assert result.returncode == 0, result.stderr
        found = re.search(r"\[vehicle\]: (drove to x=([\d.]+) m .*max after 5 s ([\d.]+) m); chain latency "
                          r"[\d.]+ ± [\d.]+ ms; \d+ deadline misses", result.stderr)
        assert found, result.stderr
        assert float(found.group(2)) > 200.0, "the car reached the end of the route"
        assert float(found.group(3)) < 0.2, "once converged, the car stays within 0.2 m of the route"
        summaries.append(found.group(1))
    assert summaries[0] == summaries[1], "the same trajectory in both mappings"


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_digit_classifier_service_accuracy(project: str) -> None:
    pytest.importorskip("sklearn")
    result = launch(EXAMPLES / "digit_classifier" / project)
    assert result.returncode == 0, result.stderr
    found = re.search(r"\[client\]: accuracy ([\d.]+) on 450 held-out digits", result.stderr)
    assert found, result.stderr
    assert float(found.group(1)) >= 0.97


def test_cnn_backward_pass_matches_finite_differences() -> None:
    sys.path.insert(0, str(EXAMPLES / "digit_classifier"))
    try:
        import cnn  # type: ignore[import-not-found]
    finally:
        sys.path.pop(0)
    rng = np.random.default_rng(1)
    params = cnn.init(rng)
    images, labels = rng.random((4, 8, 8)), rng.integers(0, 10, 4)
    _loss, grads = cnn.gradients(params, images, labels)
    for key in ("conv0", "conv2", "fc0", "bfc1"):
        flat = params[key].reshape(-1)
        for index in rng.choice(flat.size, 3, replace=False):
            saved = flat[index]
            flat[index] = saved + 1e-5
            up, _ = cnn.gradients(params, images, labels)
            flat[index] = saved - 1e-5
            down, _ = cnn.gradients(params, images, labels)
            flat[index] = saved
            numeric = (up - down) / 2e-5
            assert abs(numeric - grads[key].reshape(-1)[index]) < 1e-4 + 1e-3 * abs(numeric), key


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_lane_following_finds_the_centre_and_obeys_the_light(tmp_path: Path, project: str) -> None:
    import os

    import yaml

    example = EXAMPLES / "lane_following"
    data = yaml.safe_load((example / project).read_text())
    data["messages"] = [str((example / m).resolve()) for m in data["messages"]]
    data["nodes"]["camera"]["parameters"]["frames"] = 45
    data["nodes"]["monitor"]["parameters"].update({"frames": 45, "out": str(tmp_path / "out")})
    variant_file = tmp_path / project
    variant_file.write_text(yaml.safe_dump(data))
    result = subprocess.run([sys.executable, "-m", "hetros", "launch", str(variant_file), "--duration", "120",
                             "--node-times"],
                            capture_output=True, text=True, timeout=180, check=False,
                            env=dict(os.environ, PYTHONPATH=str(example)))
    assert result.returncode == 0, result.stderr
    found = re.search(r"centre error max ([\d.]+) px; stopped in frames \[([\d, ]*)\]", result.stderr)
    assert found, result.stderr
    assert float(found.group(1)) < 3.0, "the computed lane centre is within a few pixels of the truth"
    stopped = [int(f) for f in found.group(2).split(", ") if f]
    assert stopped == list(range(20, 35)), "stops on red (frames 20-34) and resumes on green"
    assert (tmp_path / "out" / "latency.png").stat().st_size > 0 and (tmp_path / "out" / "frame.png").exists()
    assert len(re.findall(r"node time on \S+: [\d.]+ ± [\d.]+ ms per message", result.stderr)) >= 8

"""The advisor's model, search and report on profiles written by hand, whose chain latencies can be
worked out on paper: a source, a chain of two nodes, and a side node that competes for a core."""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

import pytest
import yaml

from hetros import AdviseError
from hetros.advise import (
    Calibration,
    Chain,
    Handling,
    Limits,
    NodeProfile,
    Placement,
    Profile,
    Published,
    TopicProfile,
    measure,
    predict,
    search,
)
from hetros.advise import _search as search_module
from hetros.advise._model import fitted, one_core_mapping
from hetros.advise._observe import Observation
from hetros.advise._profile import pooled, with_one_core
from hetros.advise._report import moved, target_names, write_one_core, write_project
from hetros.advise._search import exhaustive, proposed

ROOT = Path(__file__).resolve().parents[2]
INPROC_MS, SHM_MS = 0.01, 0.1
CALIBRATION = Calibration({"host": "paper"}, {
    "inproc": [(4, INPROC_MS * 1000, INPROC_MS * 1000), (4_000_000, INPROC_MS * 1000, INPROC_MS * 1000)],
    "shm": [(4, SHM_MS * 1000, SHM_MS * 1000), (4_000_000, SHM_MS * 1000, SHM_MS * 1000)],
    "copy": [(4, 1.0, 1.0), (4_000_000, 1.0, 1.0)],
})
CHAIN = Chain("main", "/x", "/z", deadline_ms=20.0)


def constant(ms: float, count: int = 100) -> Handling:
    return Handling(count, ms, [ms] * 22, cpu=True)


def paper_profile(side_ms: float = 10.0) -> Profile:
    """camera (10 Hz, 1 ms a frame) -> /x -> a (10 ms) -> /y -> b (5 ms) -> /z; side (side_ms) also reads /x."""
    nodes = {
        "camera": NodeProfile("cam", [], {}, {"": {"/x": 10.0}}, cpu_share=0.01),
        "side": NodeProfile("p", [], {"/x": constant(side_ms)}, {}, cpu_share=side_ms / 100),
        "a": NodeProfile("p", [], {"/x": constant(10.0)}, {"/x": {"/y": 1.0}}, cpu_share=0.1),
        "b": NodeProfile("p", [], {"/y": constant(5.0)}, {"/y": {"/z": 1.0}}, cpu_share=0.05),
    }
    topics = {
        "/x": TopicProfile("m/X", 10.0, 1000, ["camera"], ["side", "a"]),
        "/y": TopicProfile("m/Y", 10.0, 1000, ["a"], ["b"]),
        "/z": TopicProfile("m/Z", 10.0, 10, ["b"], []),
    }
    return Profile("paper", "g", {"host": "paper"}, 10.0, {}, nodes, topics, {})


def on(process: str, *cpus: int) -> Placement:
    return Placement(process, cpus)


def test_one_process_adds_the_work_and_the_in_process_hops() -> None:
    """a and b alone on one core: 10 + 5 ms of work, /x from the camera's process, /y in process; side
    elsewhere."""
    mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": on("p", 0), "b": on("p", 0)}
    found = predict(paper_profile(), CALIBRATION, mapping, [CHAIN], cores=2).chains["main"]
    assert found.p50_ms == pytest.approx(SHM_MS + 10.0 + INPROC_MS + 5.0)
    assert found.p99_ms == pytest.approx(found.p50_ms)
    assert [h.node for h in found.timeline] == ["a", "b"]


def test_processes_apart_pay_shared_memory_hops() -> None:
    mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": on("pa", 0), "b": on("pb", 0)}
    found = predict(paper_profile(), CALIBRATION, mapping, [CHAIN], cores=2).chains["main"]
    assert found.p50_ms == pytest.approx(15.0 + 2 * SHM_MS)


def test_each_hop_also_wakes_its_subscriber() -> None:
    """The calibration's wake (a sleeping subscriber's, beyond the benchmark's awake one) is paid per hop."""
    waking = Calibration(CALIBRATION.machine, CALIBRATION.table, {"inproc": 0.05, "shm": 0.2})
    mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": on("p", 0), "b": on("p", 0)}
    found = predict(paper_profile(), waking, mapping, [CHAIN], cores=2).chains["main"]
    assert found.p50_ms == pytest.approx((SHM_MS + 0.2) + 10.0 + (INPROC_MS + 0.05) + 5.0)


def test_processes_pinned_to_one_core_pay_that_core_s_wake() -> None:
    """Between processes on one core the calibrated one-core wake; on different cores, or unpinned, the
    wake across cores."""
    waking = Calibration(CALIBRATION.machine, CALIBRATION.table, {"inproc": 0.05, "shm": 0.2, "shm_one_core": 0.15})
    for a, b, wake in [(on("pa", 0), on("pb", 0), 0.15), (on("pa", 0), on("pb", 1), 0.2), (on("pa"), on("pb"), 0.2),
                       (on("pa", 0, 1), on("pb", 0, 1), 0.2)]:
        mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": a, "b": b}
        found = predict(paper_profile(), waking, mapping, [CHAIN], cores=2).chains["main"]
        assert found.p50_ms == pytest.approx((SHM_MS + 0.2) + 10.0 + (SHM_MS + wake) + 5.0), (a, b)


def test_a_node_after_its_publisher_in_a_process_on_one_core_runs_at_its_one_core_times() -> None:
    """a and b measured 10 and 5 ms as mapped, 6 and 3 ms with every node in one process on one core: the
    one-core figure counts for a message from a node of the same process pinned to one core that was a
    source or warm itself (it runs right after its publisher on a core kept awake), the mapped one
    everywhere else: after a wake across processes the core is cold, and so is what follows there."""
    profile = paper_profile()
    profile.nodes["a"].one_core = {"/x": constant(6.0)}
    profile.nodes["b"].one_core = {"/y": constant(3.0)}
    cases = [
        # the camera elsewhere: a cold (its publisher is another process), and b after it
        ({"camera": on("cam", 2), "a": on("p", 0), "b": on("p", 0)}, SHM_MS + 10.0 + INPROC_MS + 5.0),
        # all in one process on one core: both warm
        ({"camera": on("p", 0), "a": on("p", 0), "b": on("p", 0)}, INPROC_MS + 6.0 + INPROC_MS + 3.0),
        # one process on two cores, or not pinned: as mapped
        ({"camera": on("p", 0, 1), "a": on("p", 0, 1), "b": on("p", 0, 1)}, INPROC_MS + 10.0 + INPROC_MS + 5.0),
        ({"camera": on("p"), "a": on("p"), "b": on("p")}, INPROC_MS + 10.0 + INPROC_MS + 5.0),
        # two processes on one core: as mapped
        ({"camera": on("cam", 0), "a": on("pa", 0), "b": on("pb", 0)}, SHM_MS + 10.0 + SHM_MS + 5.0),
    ]
    for mapping, expected in cases:
        found = predict(profile, CALIBRATION, {**mapping, "side": on("s", 2)}, [CHAIN], cores=3).chains["main"]
        assert found.p50_ms == pytest.approx(expected), mapping


# wakes of 1 ms in a process and 2 ms across
WAKING = Calibration(CALIBRATION.machine, CALIBRATION.table, {"inproc": 1.0, "shm": 2.0})


def profiled_with_one_core(one_core_p50_ms: float, mapped_p50_ms: float) -> Profile:
    """The paper profile with each node as fast in the one-core launch as mapped, and the chain's p50 in each."""
    profile = paper_profile()
    for spec in profile.nodes.values():
        spec.one_core = dict(spec.handling)
    profile.one_core_chains = {"main": {"p50_ms": one_core_p50_ms}}
    profile.chains = {"main": {"p50_ms": mapped_p50_ms}}
    return profile


def test_the_warm_hops_are_fitted_on_the_one_core_launch_and_the_others_on_the_mapping() -> None:
    """Wakes of 1 ms in a process and 2 ms across. The one-core launch (every node in one process on one
    core: side first, then a) measured 26.02 ms where the model without wakes says 25.02 and with them
    27.02: warm hops pay half. The mapping profiled (the camera's process elsewhere, a and b in one on
    core 0) measured 16.61 ms: 15.61 without the cross-process wake (the warm hop a -> b at half), 17.61
    with it: the other hops pay half too."""
    profile = profiled_with_one_core(26.02, 16.61)
    mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": on("p", 0), "b": on("p", 0)}
    fit, how = fitted(profile, WAKING, mapping, [CHAIN], cores=2)
    assert (fit.warm_scale, fit.wake_scale) == (pytest.approx(0.5), pytest.approx(0.5))
    assert "within a process on one core 0.50" in how
    # no one-core launch: warm hops pay what the others do
    profile.one_core_chains = {}
    fit, _ = fitted(profile, WAKING, mapping, [CHAIN], cores=2)
    assert fit.warm_scale == fit.wake_scale == pytest.approx((16.61 - 15.11) / 3.0)


def test_the_one_core_launch_leaves_ros1_and_remote_nodes_where_they_were() -> None:
    """A camera on ROS 1 stays in its own process in the one-core launch, which measured 27.61 ms: the
    camera's hop across processes (0.1 + a 2 ms wake), side and a (20), the warm hop a -> b (0.01 + the
    1 ms wake at the warm scale) and b (5) make 27.11 without that wake: warm hops pay half. Taking the
    camera into the one process (25.02 without the warm wakes, two of them) would fit 1.295."""
    profile = profiled_with_one_core(27.61, 16.61)
    mapping = {"camera": on("ros1_camera"), "side": on("s", 1), "a": on("p", 0), "b": on("p", 0)}
    launch = one_core_mapping(mapping, ["side", "a", "b"])
    together = Placement("advise_one_core", (0,))
    assert launch == {"camera": on("ros1_camera"), "side": together, "a": together, "b": together}
    fit, _ = fitted(profile, WAKING, mapping, [CHAIN], cores=2, one_core=launch)
    assert fit.warm_scale == pytest.approx(0.5)
    assumed, _ = fitted(profile, WAKING, mapping, [CHAIN], cores=2)
    assert assumed.warm_scale == pytest.approx(1.295)


def test_a_side_node_in_the_same_process_makes_the_chain_wait() -> None:
    """side subscribes /x before a: one process takes them in turn, so a starts 10 ms late."""
    mapping = {"camera": on("cam", 1), "side": on("p", 0), "a": on("p", 0), "b": on("p", 0)}
    found = predict(paper_profile(), CALIBRATION, mapping, [CHAIN], cores=2).chains["main"]
    assert found.p50_ms == pytest.approx(SHM_MS + 25.0 + INPROC_MS)
    assert found.waiting_ms["a"] == pytest.approx(10.0)
    assert found.dominant() == "a"


def test_two_processes_on_one_core_share_it() -> None:
    """side and a start together on one core: each gets half of it until side ends at 20 ms."""
    mapping = {"camera": on("cam", 1), "side": on("s", 0), "a": on("p", 0), "b": on("p", 0)}
    prediction = predict(paper_profile(), CALIBRATION, mapping, [CHAIN], cores=2)
    found = prediction.chains["main"]
    # /x reaches both at 0.1 ms; both progress at half speed: a ends at 0.1 + 20 = 20.1; b: +0.01 + 5
    assert found.p50_ms == pytest.approx(SHM_MS + 20.0 + INPROC_MS + 5.0)
    assert prediction.core_load[0] == pytest.approx(0.25, abs=0.01)  # 25 ms of work each 100 ms


def test_the_search_separates_what_competes_and_meets_the_deadline() -> None:
    profile = paper_profile()
    original = {"camera": on("cam"), "side": on("p", 0), "a": on("p", 0), "b": on("p", 0)}
    ranked, how = search(profile, CALIBRATION, original, [(CHAIN, ["a", "b"])], Limits(cores=2), keep=3)
    assert "all" in how
    best = ranked[0]
    assert best.meets([CHAIN])
    assert best.mapping["side"].cpus != best.mapping["a"].cpus
    assert best.mapping["a"] == best.mapping["b"]  # together: in-process hops
    assert best.prediction.chains["main"].p50_ms == pytest.approx(15.0 + 2 * INPROC_MS)  # the camera joins them


def test_pinned_nodes_stay_and_cores_are_counted_once() -> None:
    profile = paper_profile()
    original = {"camera": on("cam"), "side": on("p", 0), "a": on("p", 0), "b": on("p", 0)}
    options = search_module.choices(profile, original, Limits(cores=2, pinned=frozenset({"camera"})))
    assert options["camera"] == [on("cam")]
    found = list(exhaustive(options, 2))
    assert len(found) == 4  # three nodes on two interchangeable cores: all on one, or one of three apart
    assert all(m["camera"] == on("cam") for m in found)
    assert search_module._count(options, True, 2) == len(found)


def test_the_solver_proposes_what_the_simulation_ranks_best(monkeypatch: pytest.MonkeyPatch) -> None:
    profile = paper_profile()
    original = {"camera": on("cam"), "side": on("p", 0), "a": on("p", 0), "b": on("p", 0)}
    options = search_module.choices(profile, original, Limits(cores=2))
    mappings = proposed(profile, CALIBRATION, options, [(CHAIN, ["a", "b"])], 2, count=4, time_limit_s=10)
    assert mappings and len({tuple(sorted(m.items())) for m in mappings}) == len(mappings)
    first = mappings[0]
    assert first["side"].cpus != first["a"].cpus and first["a"] == first["b"]
    monkeypatch.setattr(search_module, "EXHAUSTIVE_LIMIT", 1)
    ranked, how = search(profile, CALIBRATION, original, [(CHAIN, ["a", "b"])], Limits(cores=2), keep=2)
    assert "HiGHS" in how and ranked[0].meets([CHAIN])


def test_a_deadline_no_mapping_meets_is_told_with_the_dominant_node() -> None:
    from hetros.advise import Advice

    profile = paper_profile()
    tight = Chain("main", "/x", "/z", deadline_ms=12.0)
    original = {"camera": on("cam"), "side": on("p", 0), "a": on("p", 0), "b": on("p", 0)}
    limits = Limits(cores=2)
    ranked, how = search(profile, CALIBRATION, original, [(tight, ["a", "b"])], limits)
    advice = Advice(profile, "paper", ranked[-1], ranked, how, [(tight, ["a", "b"])], limits,
                    {n: "t" for n in original})
    text = advice.shortfall()
    assert "3.0 ms over its 12 ms deadline" in text and "a dominates (10.0 ms working" in text


def test_hardware_nodes_stream_within_a_target() -> None:
    """a and b in hardware on one target: b works beside a (dataflow), so the chain takes the longer
    of the two plus the gateway's copies, not their sum."""
    profile = paper_profile()
    profile.nodes["a"].hardware = {"ms": 4.0, "resources": {"lut": 10}}
    profile.nodes["b"].hardware = {"ms": 3.0, "resources": {"lut": 10}}
    mapping = {"camera": on("cam", 1), "side": on("s", 1), "a": Placement("fpga", (), True),
               "b": Placement("fpga", (), True)}
    found = predict(profile, CALIBRATION, mapping, [CHAIN], cores=2).chains["main"]
    copy_ms = CALIBRATION.latency_ms("copy", 1000)
    # into hardware: one copy and a shared-memory hop; a 4 ms; b already done beside it
    assert found.p50_ms == pytest.approx(copy_ms + SHM_MS + 4.0)
    apart = dict(mapping, b=on("pb", 0))
    sequential = predict(profile, CALIBRATION, apart, [CHAIN], cores=2).chains["main"]
    assert sequential.p50_ms == pytest.approx(copy_ms + SHM_MS + 4.0 + copy_ms + SHM_MS + 5.0)


def test_measured_chains_match_by_stamp_or_by_the_newest_message() -> None:
    first = [Published(1_000_000 * t, 10, t) for t in (100, 200, 300)]
    last = [Published(1_000_000 * t + 15_000_000, 10, t) for t in (100, 200, 300)]
    found = measure(first, last)
    assert found is not None and found.matched_by == "header stamp" and found.p50_ms == pytest.approx(15.0)
    bare = [Published(p.time_ns, 10, None) for p in last]
    found = measure([Published(p.time_ns, 10, None) for p in first], bare)
    assert found is not None and found.matched_by.startswith("newest") and found.p50_ms == pytest.approx(15.0)
    assert measure(first, []) is None


def test_a_mapping_launched_several_times_is_the_median_of_its_launches() -> None:
    from hetros.advise._chains import ChainLatency, over_launches

    launches = [ChainLatency(0.4, 0.9, 500, "header stamp"), None, ChainLatency(0.8, 1.6, 480, "header stamp"),
                ChainLatency(0.5, 1.1, 490, "header stamp")]
    combined = over_launches(launches)
    assert combined is not None
    assert (combined.p50_ms, combined.p99_ms, combined.samples) == (0.5, 1.1, 1470)
    assert combined.launch_p50s_ms == (0.4, 0.8, 0.5) and combined.as_dict()["launch_p50s_ms"] == [0.4, 0.8, 0.5]
    assert over_launches([launches[0]]) is launches[0] and "launch_p50s_ms" not in launches[0].as_dict()
    assert over_launches([None, None]) is None


@pytest.mark.parametrize(("text", "problem"), [
    ("/x", "must be written"), ("/x:/y@-3ms", "must be written"), ("/x:/y@0ms", "positive"),
])
def test_chains_are_written_one_way(text: str, problem: str) -> None:
    with pytest.raises(AdviseError, match=problem):
        Chain.parse(text)


def test_a_chain_is_parsed_with_its_name_and_deadline() -> None:
    assert Chain.parse("alpha=/image_raw:/cmd_vel@30ms") == Chain("alpha", "/image_raw", "/cmd_vel", 30.0)
    assert Chain.parse("/a:/b").name == "/a->/b"


def test_a_chain_the_graph_cannot_carry_is_refused() -> None:
    from hetros.project import plan_file

    plan = plan_file(ROOT / "examples/lane_following/project.yaml")
    assert Chain.parse("/image_raw:/cmd_vel").check(plan) == [
        "compensation", "gaussian_blur", "red_light", "green_light", "projection", "lane_control", "lane_following"]
    with pytest.raises(AdviseError, match="no topic /nope"):
        Chain.parse("/image_raw:/nope").check(plan)
    with pytest.raises(AdviseError, match="no node path leads from /cmd_vel to /image_raw"):
        Chain.parse("/cmd_vel:/image_raw").check(plan)


def test_the_one_core_launch_puts_this_machine_s_nodes_in_one_process_and_nothing_else(tmp_path: Path) -> None:
    source = tmp_path / "project.yaml"
    source.write_text(yaml.safe_dump({
        "name": "p", "hosts": {"here": {"address": "127.0.0.1"}, "there": {"address": "10.0.0.2"}},
        "targets": {"a": {"kind": "process", "cpus": [1]}, "b": {"kind": "process"}, "t": {"kind": "thread"},
                    "far": {"kind": "process", "host": "there", "cpus": [3]}, "old": {"kind": "ros1"},
                    "hw": {"kind": "fpga"}},
        "nodes": {"n": {"run": "m:n", "target": "a"}, "m": {"run": "m:m", "target": "t", "parameters": {"k": 1}},
                  "f": {"run": "m:f", "target": "far"}, "r": {"run": "m:r", "target": "old"},
                  "h": {"run": "m:h", "hw": "x:y", "target": "hw"}}}))
    written = yaml.safe_load(write_one_core(source, 0, tmp_path / "one.yaml").read_text())
    assert written["targets"] == {"far": {"kind": "process", "host": "there", "cpus": [3]}, "old": {"kind": "ros1"},
                                  "hw": {"kind": "fpga"}, "advise_one_core": {"kind": "process", "cpus": [0]}}
    assert {name: entry["target"] for name, entry in written["nodes"].items()} == \
        {"n": "advise_one_core", "m": "advise_one_core", "f": "far", "r": "old", "h": "hw"}
    assert written["nodes"]["m"]["parameters"] == {"k": 1}
    source.write_text("name: p\ntargets: [a]\nnodes: {}\n")
    with pytest.raises(AdviseError, match="must be mappings written out"):
        write_one_core(source, 0, tmp_path / "one.yaml")


def test_the_written_project_differs_only_in_targets(tmp_path: Path) -> None:
    from hetros.advise import mapping_of
    from hetros.project import plan_file

    source = ROOT / "examples/lane_following/project.yaml"
    plan = plan_file(source)
    original, targets = mapping_of(plan)
    candidate = dict(original)
    candidate["green_light"] = Placement("core1", (1,))
    candidate["red_light"] = Placement("core1", (1,))
    assert target_names(original, original, targets) == targets
    assert moved(candidate, original, targets) == ["green_light chain_a->core1", "red_light chain_a->core1"]
    out = write_project(source, candidate, original, targets, tmp_path / "advised.yaml")
    before, after = yaml.safe_load(source.read_text()), yaml.safe_load(out.read_text())
    assert after["targets"]["core1"] == {"kind": "process", "cpus": [1]}
    for key in set(before) | set(after):
        if key not in ("targets", "nodes"):
            assert before[key] == after[key]
    for node, entry in before["nodes"].items():
        assert {k: v for k, v in entry.items() if k != "target"} == \
            {k: v for k, v in after["nodes"][node].items() if k != "target"}
    assert after["nodes"]["red_light"]["target"] == "core1"
    assert after["nodes"]["compensation"]["target"] == "chain_a"


def test_a_profile_survives_its_file_and_knows_where_it_was_taken(tmp_path: Path) -> None:
    profile = paper_profile()
    with_one_core(profile, paper_profile(side_ms=3.0))
    assert profile.nodes["side"].one_core["/x"].mean_ms == 3.0
    profile.save(tmp_path / "profile.json")
    again = Profile.load(tmp_path / "profile.json")
    assert again == profile
    (tmp_path / "bad.json").write_text('{"format": 99}')
    with pytest.raises(AdviseError, match="format 1 expected"):
        Profile.load(tmp_path / "bad.json")
    from hetros.project import plan_file

    warnings = again.fits(plan_file(ROOT / "examples/lane_following/project.yaml"))
    assert any("another graph" in w for w in warnings) and any("another machine" in w for w in warnings)


def test_a_tapped_message_reaches_the_hardware_as_its_body() -> None:
    """A tap gives the wire's bytes (encapsulation, then the body, padded); a hardware port takes the body
    alone. Fed the wire's bytes, the vehicle's filters read the encapsulation as the stamp and took four
    times the cycles of a frame."""
    import numpy as np

    from hetros.advise._hardware import _body
    from hetros.msg import registry
    from hetros.transport import MessageCodec

    types = registry()
    image = types.get("sensor_msgs/msg/Image")(height=2, width=3, encoding="rgb8", step=9,
                                                  data=np.arange(18, dtype=np.uint8))
    image.header.frame_id = "frame7"
    wire = bytes(MessageCodec(types, "sensor_msgs/msg/Image").encode(image)) + b"\0\0"
    body = _body(types, "sensor_msgs/msg/Image", wire)
    assert body == wire[4:-2]
    assert body[8:12] == (7).to_bytes(4, "little") and body[12:18] == b"frame7"  # frame_id right after the stamp


def test_a_chain_through_hardware_is_placed_in_co_simulated_time(tmp_path: Path) -> None:
    """source -> /a -> echo (hardware) -> /b -> soft -> /c; a software branch /a -> side -> /e; join /c, /e ->
    /f. The co-simulation kept /b a whole millisecond in wall time; its gateway counted 50 µs simulated and
    10 µs of copies, and a hop into it costs 20 µs. So /b is at 80 µs, /c at 80 + 300 = 380 µs (soft's
    measured 0.3 ms), /e at 500 µs (wall: no hardware on the way), /f at max(380, 500) + 100 = 600 µs."""
    from hetros.advise._chains import HardwareSpan, cosimulated_latency
    from hetros.project import plan_file

    header = "std_msgs/msg/Header"
    (tmp_path / "project.yaml").write_text(yaml.safe_dump({
        "name": "cosim", "targets": {"io": {"kind": "process"}, "fpga": {"kind": "fpga", "data_width": 32}},
        "nodes": {
            "source": {"run": "json:dumps", "target": "io", "publish": {"/a": header}},
            "echo": {"run": "json:dumps", "hw": "hetros.hw.nodes:Echo", "target": "fpga",
                     "parameters": {"source": "/a", "sink": "/b"}, "subscribe": {"/a": header},
                     "publish": {"/b": header}},
            "soft": {"run": "json:dumps", "target": "io", "subscribe": {"/b": header}, "publish": {"/c": header}},
            "side": {"run": "json:dumps", "target": "io", "subscribe": {"/a": header}, "publish": {"/e": header}},
            "join": {"run": "json:dumps", "target": "io", "subscribe": {"/c": header, "/e": header},
                     "publish": {"/f": header}}}}))
    plan = plan_file(tmp_path / "project.yaml")
    stamp = 7_000_000_123
    at = {"/a": 0, "/b": 1_000_000, "/c": 1_300_000, "/e": 500_000, "/f": 1_400_000}
    published = {topic: [Published(time_ns, 64, stamp)] for topic, time_ns in at.items()}
    published["/a"].append(Published(9_000_000, 64, stamp + 1))  # a message that never went through
    spans = {("/b", stamp): HardwareSpan(sim_ns=50_000, cpu_ns=10_000)}
    chain = Chain("f", "/a", "/f")
    found = cosimulated_latency(plan, chain, published, spans, lambda _topic, _size: 20_000.0)
    assert found is not None and found.samples == 1
    assert found.p50_ms == pytest.approx(0.6)
    through = cosimulated_latency(plan, Chain("c", "/a", "/c"), published, spans, lambda _t, _s: 20_000.0)
    assert through is not None and through.p50_ms == pytest.approx(0.38)
    assert cosimulated_latency(plan, chain, published, {}, lambda _t, _s: 20_000.0) is None  # no span: not placed


def test_a_gateway_counts_each_stamped_message_in_simulated_time() -> None:
    """At 100 MHz (10 ns a cycle): in at cycle 1000, out at 1500: 5 µs. The next went in at 1200, while the
    hardware still sent the first: it counts from 1500 (a real target, fed at the real rate, would not have
    queued it), out at 1900: 4 µs. Copies add up; an unstamped message is not timed."""
    from hetros.launch.system._gateway import CoSimulatedTimes
    from hetros.msg import registry

    stamped = registry().get("geometry_msgs/msg/PointStamped")
    first, second = stamped(), stamped()
    first.header.stamp.sec, second.header.stamp.sec = 1, 2
    times = CoSimulatedTimes(100.0)
    times.entered(first, 1000, 5)
    times.entered(second, 1200, 6)
    times.entered(registry().get("std_msgs/msg/Empty")(), 1300, 1)
    times.left("/out", first, 1500, 7)
    times.left("/out", second, 1900, 8)
    assert times.spans() == [{"stamp": 1_000_000_000, "topic": "/out", "sim_ns": 5000, "cpu_ns": 12},
                             {"stamp": 2_000_000_000, "topic": "/out", "sim_ns": 4000, "cpu_ns": 14}]


def test_a_profile_of_several_launches_pools_them() -> None:
    """Quantiles averaged point by point, counts added, means weighted by count, rates and CPU shares
    averaged; a chain's p50 the median of the launches' (1, 3 and 2 ms: 2)."""
    launches, observations = [], []
    for k, (handling_ms, chain_ms) in enumerate([(10.0, 1.0), (20.0, 3.0), (30.0, 2.0)]):
        profile = paper_profile()
        profile.nodes["a"].handling["/x"] = Handling(100 * (k + 1), handling_ms, [handling_ms] * 22, cpu=True)
        profile.nodes["a"].cpu_share = 0.1 * (k + 1)
        profile.topics["/x"].rate_hz = 10.0 + k
        launches.append(profile)
        published = {"/x": [Published(t * 100_000_000, 8, None) for t in range(10)],
                     "/z": [Published(t * 100_000_000 + int(chain_ms * 1e6), 8, None) for t in range(10)]}
        observations.append(Observation(cast(Any, None), 1.0, published=published))
    pooled_profile = pooled(launches, observations, [CHAIN])
    a = pooled_profile.nodes["a"].handling["/x"]
    assert a.count == 600
    assert a.quantiles_ms == pytest.approx([20.0] * 22)
    assert a.mean_ms == pytest.approx((100 * 10.0 + 200 * 20.0 + 300 * 30.0) / 600)
    assert pooled_profile.nodes["a"].cpu_share == pytest.approx(0.2)
    assert pooled_profile.topics["/x"].rate_hz == pytest.approx(11.0)
    chain = pooled_profile.chains["main"]
    assert chain["p50_ms"] == pytest.approx(2.0)
    assert chain["launch_p50s_ms"] == pytest.approx([1.0, 3.0, 2.0])
    assert chain["samples"] == 30
    assert pooled([launches[0]], observations[:1], [CHAIN]) is launches[0]


def test_a_calibration_measured_busy_or_on_another_clock_no_longer_holds(monkeypatch: pytest.MonkeyPatch) -> None:
    """A calibration cached from a loaded machine was reused silently (a 3 kB hop of 1,055 µs where 16 µs was
    measured later): one measured busy, or whose copy now takes another time, is measured again."""
    from hetros.advise import _calibrate

    copy_us = {"now": 6.5}
    monkeypatch.setattr(_calibrate, "copy_check_us", lambda: copy_us["now"])
    table = {"copy": [(4, 0.5, 0.6), (196608, 6.5, 8.0)]}
    assert Calibration({"busy": 0.05}, table).stale() == ""
    assert Calibration({}, table).stale() == ""  # cached before the conditions were kept: checked by its copy
    assert Calibration({"busy": 0.6}, table).stale() == "it was measured while 60% of the CPUs were busy"
    copy_us["now"] = 13.0
    assert Calibration({"busy": 0.0}, table).stale() == "a copy of 192 kB takes 13.0 µs now, 6.5 µs then"
    copy_us["now"] = 5.0
    assert Calibration({"busy": 0.0}, table).stale() == ""  # within 1.5x either way


def test_the_busy_share_of_the_machine_is_read_from_the_kernel() -> None:
    from hetros.advise._measure import busy_share

    assert 0.0 <= busy_share(0.05) <= 1.0

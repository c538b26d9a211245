"""The latency report's arithmetic: pooled rounds and the per-round overhead ratio."""

from __future__ import annotations

import pytest

from hetros_bench.latency import SIZES, Result, Run, parse_sizes, pooled, render, round_ratio


def _result(system: str, rtt_us: list[float], size: int = 4) -> Result:
    samples = [int(v * 1000) for v in rtt_us]
    return Result.measured(system, size, samples, samples)


def test_a_phase_that_hit_one_round_of_one_row_moves_one_ratio_not_the_median() -> None:
    run = Run()
    run.rounds[("hetros-shm", 4)] = [_result("hetros-shm", [20.0]), _result("hetros-shm", [200.0]),
                                     _result("hetros-shm", [22.0])]
    run.rounds[("iceoryx2", 4)] = [_result("iceoryx2", [10.0]), _result("iceoryx2", [10.0]),
                                   _result("iceoryx2", [10.0])]
    assert round_ratio(run, "hetros-shm", "iceoryx2", 4) == 2.2
    pooled_mean = pooled(run.rounds[("hetros-shm", 4)]).rtt
    assert pooled_mean is not None and round(pooled_mean.mean, 6) == 80.666667, "pooling keeps every sample"


def test_an_even_number_of_rounds_takes_the_middle_two_and_a_missing_row_gives_no_ratio() -> None:
    run = Run()
    run.rounds[("hetros-shm", 4)] = [_result("hetros-shm", [v]) for v in (20.0, 30.0)]
    run.rounds[("iceoryx2", 4)] = [_result("iceoryx2", [10.0]) for _ in range(2)]
    assert round_ratio(run, "hetros-shm", "iceoryx2", 4) == 2.5
    assert round_ratio(run, "hetros-shm-loan", "iceoryx2", 4) is None


def test_the_overhead_table_shows_the_median_ratio() -> None:
    run = Run()
    for system, values in (("hetros-shm", (20.0, 200.0, 22.0)), ("iceoryx2", (10.0, 10.0, 10.0))):
        run.rounds[(system, 4)] = [_result(system, [v]) for v in values]
    run.results = [pooled(results) for results in run.rounds.values()]
    report = render(run, ["hetros-shm", "iceoryx2"], [4])
    overhead = report.split("### Framework overhead")[1]
    assert "| 4 B | 2.20x |" in overhead


def test_the_ported_ping_pong_is_compared_round_by_round_and_less_the_floor() -> None:
    run = Run()
    for system, values in (("hetros-rclpy-pp", (12.0, 30.0, 11.0)), ("hetros-rospy-pp", (30.0, 30.0, 30.0)),
                           ("hetros-rospy-pp-cb", (11.0, 16.5, 11.0)), ("hetros-shm-cb", (10.0, 15.0, 10.0))):
        run.rounds[(system, 4)] = [_result(system, [v]) for v in values]
    run.results = [pooled(results) for results in run.rounds.values()]
    run.handover = {"event_wait_us": 14.1, "one_thread_us": 0.1, "floor_us": 14.0}
    report = render(run, ["hetros-shm-cb", "hetros-rclpy-pp", "hetros-rospy-pp", "hetros-rospy-pp-cb"], [4])
    both = report.split("### Both ends")[1].split("###")[0]
    assert "| 4 B | 1.20x | 3.00x | 1.10x |" in both, "rounds 1.2, 2.0 and 1.1: the median, not the pooled 1.53"
    assert "| 4 B | 1.60x |" in report.split("less that floor")[1], "(30 - 14) / 10 in rounds 1 and 3"


def test_sizes_are_chosen_by_label_or_bytes_in_the_benchmarks_order_and_an_unknown_one_is_named() -> None:
    assert parse_sizes("3146kB, 4B,196608", SIZES) == [4, 196608, 3145728]
    with pytest.raises(ValueError, match=r"--sizes: each size must be one of 4B, .* not '5kB'"):
        parse_sizes("4B,5kB", SIZES)


@pytest.mark.parametrize("bench", ["latency", "ros1"])
def test_the_cli_forwards_sizes_to_the_benchmark(bench: str, monkeypatch: pytest.MonkeyPatch) -> None:
    import hetros_bench.latency
    import hetros_bench.ros1
    from hetros.cli import build_parser

    seen: list[list[str]] = []
    module = hetros_bench.latency if bench == "latency" else hetros_bench.ros1
    monkeypatch.setattr(module, "main", lambda argv: seen.append(argv) or 0)
    args = build_parser().parse_args(["bench", bench, "--sizes", "4B,196kB"])
    assert args.func(args) == 0
    assert seen and seen[0][seen[0].index("--sizes") + 1] == "4B,196kB"


def test_a_loan_slower_than_a_plain_publish_at_large_sizes_fails_the_run() -> None:
    """The benchmark's guard of the zero-copy path: from 196 kB a loaned publish must not lose to a copy."""
    from hetros_bench.latency import Stats, loan_regressions

    def row(system: str, size: int, p50: float) -> Result:
        return Result(system, size, one_way=Stats(p50, 1.0, p50, p50, 100))

    fine = [row("hetros-shm", 196608, 15.8), row("hetros-shm-loan", 196608, 13.1),
            row("hetros-shm", 3145728, 67.9), row("hetros-shm-loan", 3145728, 70.8),  # one copy each: noise
            row("hetros-shm", 4, 5.0), row("hetros-shm-loan", 4, 6.0)]  # small: a loan may cost a little
    assert loan_regressions(fine) == []
    slow = [row("hetros-shm", 3145728, 229.0), row("hetros-shm-loan", 3145728, 643.0)]
    assert loan_regressions(slow) == ["hetros-shm-loan is slower than hetros-shm at 3146 kB: p50 643.0 µs against "
                                      "229.0 µs"]

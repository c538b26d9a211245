"""Benchmarks of hetros against its peers (``hetros bench latency``); needs ``hetros[bench]``."""

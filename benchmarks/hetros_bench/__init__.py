"""Benchmarks of hetros against its peers: the roles and peers behind ``hetros bench`` and the scripts
beside this package. Not part of the installed library: ``make install-bench`` (or ``pip install -e
benchmarks``) installs it with the peers (``hetros[bench]``)."""

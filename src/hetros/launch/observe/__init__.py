"""Looking at a running launch without changing it: control sockets and taps, inspection, recording and
play (MCAP), the Foxglove server, the launch's logs."""

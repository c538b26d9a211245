"""The hardware nodes hetros ships (image filters, the sorter, memory nodes, hardware TCPROS programs) and
the wrapping of Verilog ones; ``hetros.hw.nodes`` is their public face."""

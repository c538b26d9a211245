"""Running the hardware without a board: Verilator and Amaranth co-simulation of a target, Icarus and
Amaranth runs of topic networks, execution models and reports."""

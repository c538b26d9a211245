"""An fpga target's top module: its nodes and topic networks wired to gateway ports, the manifest, and
the design key its clock and simulator cache are kept under."""

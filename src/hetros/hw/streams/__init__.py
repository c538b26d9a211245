"""The wire of hardware topics: AXI4-Stream parts, message beats, byte gearboxes and the port names
nodes and builders share."""

"""A node module that fails on import: `hetros check` must say so, not the launch."""

raise ValueError("this module is broken on import")

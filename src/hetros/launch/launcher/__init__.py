"""The launcher and its workers: start a plan's process targets, supervise them, stop them in order;
meet other hosts and deploy to them; the per-user record of running launches."""

"""Towards a real part: the open flow's bitstream and Fmax, and the board export for Vivado."""

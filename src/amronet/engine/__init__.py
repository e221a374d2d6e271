"""The simulator's engine: robots, neighbours, radio, network, sensing, motion, coverage and random streams.

Robot state arrays, the neighbour index, the radio medium, the network graph, range sensing, motion with
collision checks, coverage (Eq. 1) and per-run random streams. Everything here works on NumPy arrays for all
robots at once and knows nothing of algorithms, scenarios or outputs.
"""

"""Analyses of the model and of runs.

- modes: static deflection, modes, Campbell diagram
- critical: critical speeds
- critical_map: critical speeds over (r0, delta)
- coupling_drift: exact against the paper's coupling
- stages: the four stages of the Eq. 26 run
- alignment: the delay between a measured run and its profile
"""

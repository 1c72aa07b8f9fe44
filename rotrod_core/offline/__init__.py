"""Offline simulation.

- simulate: one run, Magnus in velocity drive
- batch: many runs at once
- result: the run and its derived quantities
"""

"""Numerical building blocks, with no physics.

- checks: finite-value checks and the non-finite-state error
- expm: batched matrix exponentials
- rk4: one classical Runge-Kutta step
"""

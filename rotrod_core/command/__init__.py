"""Commands for the hub.

- profiles: angular-velocity profiles and their one registry
- shaping: a stream of setpoints shaped into a physical w(t)
- planner: the fastest vibration-free spin-up
"""

"""Commands for the hub.

- profiles: angular-velocity profiles (classes, and make_profile by class name)
- shaping: a stream of setpoints shaped into a physical w(t)
- planner: the fastest vibration-free spin-up
- registry: the named profiles built from options (CLI and profile publisher),
  the planned spin-up among them
"""

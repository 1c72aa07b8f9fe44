"""The live engine a node drives, with no ROS import.

- engine: commands, limits, health
- stepper: the real-time integrator
- pacing: wall-clock pacing and stamps
- scheduling: CPU scheduling and latency requests
"""

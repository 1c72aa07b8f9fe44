"""The live engine a node drives, with no ROS import.

- engine: commands, limits, health
- loop: the real-time loop (pacing, command queue, publication timing)
- stepper: the real-time integrator
- pacing: wall-clock pacing and stamps
- scheduling: CPU scheduling and latency requests
"""

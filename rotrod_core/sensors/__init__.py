"""What a real rig measures: its sensors' models over the simulated motion.

- noise: SDF's ``<noise>`` (Gaussian, bias, Gauss-Markov dynamic bias, quantisation)
  as Gazebo applies it, seeded per channel
- imu: the tip IMU's frame (tilted by the rod's slope), angular velocity and specific
  force
- encoder: the hub encoder's counts, their angle and the speed from counts
"""

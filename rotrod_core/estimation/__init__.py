"""Estimation from motion.

- whirl: whirl frequencies and amplitudes (maximum likelihood)
- trajectory_fit: a two-whirl fit of a whole record
- identify: rig stiffness, mass and eccentricity from motion
- monitor: the rig monitor, online identification
"""

"""Estimation from motion.

- whirl: whirl frequencies and amplitudes by maximum likelihood, over a sliding
  window (WhirlEstimator) or a whole record (fit_whirls)
- identify: rig stiffness, mass and eccentricity from motion
- monitor: the rig monitor, online identification
"""

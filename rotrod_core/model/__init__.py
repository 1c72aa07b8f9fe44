"""The model: the rod's parameters, beam formulas and equations of motion.

- params: RodParams, SI units, Table 1 defaults
- beam: cantilever stiffness under axial load, Rayleigh-Ritz modal masses
- equations: the equations of motion (docs/model.md), the coupling check
- geometry: the deflected rod's centreline, for drawing
"""

"""The model: the rod's parameters, beam formulas and equations of motion.

- params: RodParams, SI units, Table 1 defaults
- beam: cantilever stiffness under axial load, Rayleigh-Ritz modal masses
- equations: the equations of motion (docs/model.md), the coupling check
- geometry: the deflected rod's centreline, for drawing
- scene: the drawn shapes (disk, rod, mass, trail) behind the markers
- interface: frame, joint and topic names, joint values, stamps (live node, URDF, bags)
- urdf: the URDF generated from RodParams; RodParams from ROS 2 parameter files
"""

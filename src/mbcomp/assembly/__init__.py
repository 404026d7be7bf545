"""Assembly: topology (spanning tree, cut joints), kinematic jets, the assembled system,
consistent initialization, the constraint manifold and the model summary.
"""

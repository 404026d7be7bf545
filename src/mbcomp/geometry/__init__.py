"""Geometry: rotations, quaternions, homogeneous transforms and relative motion.

The first layer of the pipeline; it imports nothing else of mbcomp. ``kinematics`` holds
the fast numeric helpers the assembler uses, ``rotations`` and ``relative_motion`` the
textbook's toolkit (sympy or numpy, chosen by the input: ``symbolic``).
"""

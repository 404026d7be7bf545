"""Modelling: components, their parameters and ports, the role contracts, models, inertia.

Imports only :mod:`mbcomp.geometry` and :mod:`mbcomp.errors`. The one joint the framework
itself needs (:mod:`~mbcomp.modeling.free_joint`: the free joint the topology inserts for
floating bodies) lives here too, and so does the loader of model files
(:mod:`~mbcomp.modeling.loader`: ``build(**params) -> Model``).
"""

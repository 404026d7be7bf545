"""Analysis on top of simulation: steady states, linearization and stability, sweeps,
work-precision studies."""
from .stability import *  # noqa: F401,F403
from .stability import __all__ as _stability_all
from .stability import __doc__ as __doc__  # noqa: F401  (mbcomp.stability's documentation)

__all__ = list(_stability_all)

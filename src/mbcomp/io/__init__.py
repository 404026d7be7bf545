"""Robot description files read into a :class:`~mbcomp.Model` of library components.

This package sits above the pipeline, as ``mbcomp/__init__.py`` does: it builds models of
the component library (imported inside its functions, on call, so that importing the
framework never imports the library).
"""

"""Robot description files read into a :class:`~mbcomp.Model` of library components.

This package is the pipeline's last layer but the command line (``cli/`` reads ``.urdf`` and
``.xml`` files through it). It is a *model author*, as a user's model file is: it builds
models of the component library, imported inside its functions, on call, so that importing
the framework never imports the library (``tests/framework/test_layout.py`` MODEL_AUTHORS).
"""

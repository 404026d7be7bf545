"""Component names of imported robots: the file's names where they are identifiers, else sanitized.

Shared by the URDF and MJCF importers (:mod:`mbcomp.io.urdf`, :mod:`mbcomp.io.mjcf`).
"""
import re

__all__ = ["ComponentNames"]


class ComponentNames:
    """Unique component names: the file's name where it is an identifier, else sanitized
    (``\\W`` -> ``_``, a leading digit prefixed with ``_``), made unique with ``_2``, ``_3``,
    ...; ``world`` is reserved. Every change is appended to ``notes``.

    Parameters
    ----------
    notes : list of str
        Where the renames are said (``model.urdf_notes``, ``model.mjcf_notes``).

    Examples
    --------
    >>> from mbcomp.io.names import ComponentNames
    >>> notes = []
    >>> names = ComponentNames(notes)
    >>> names("j-1", "joint"), names("j_1", "joint"), names("world", "body")
    ('j_1', 'j_1_2', 'world_2')
    >>> len(notes)
    3
    """

    def __init__(self, notes):
        self.notes, self.used = notes, set()

    def __call__(self, name, what):
        """The component name of the file's ``name`` (an element of kind ``what``: "joint", "link", ...)."""
        new = self.sanitized(name)
        base, k = new, 1
        while new in self.used or new == "world":
            k += 1
            new = f"{base}_{k}"
        if new != name:
            self.notes.append(f"{what} {name!r}: named {new!r} in the model (component names are identifiers)")
        self.used.add(new)
        return new

    @staticmethod
    def sanitized(name):
        """``name`` as an identifier (non-word characters -> ``_``, a leading digit prefixed with ``_``)."""
        new = re.sub(r"\W", "_", name)
        return "_" + new if not new or new[0].isdigit() else new

    def taken(self, name):
        """Whether ``name`` (sanitized) is a component name given already."""
        return self.sanitized(name) in self.used

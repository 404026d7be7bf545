"""Seeing a mechanism: its scene (default and declared shapes, the pose of every link over a
run), the self-contained HTML player, matplotlib pictures and films, and the drawing of the
assembled topology.

The stage sits after the assembly and before the simulation driver: it reads an assembled
system and a result's columns and never changes either. Nothing here is imported by
``import mbcomp`` or by a simulation; matplotlib and the vendored three.js are read only when
a picture or a player is asked for.
"""

"""What an MJCF file holds that :func:`mbcomp.load_mjcf` does not import, said element by element.

Actuators are listed one by one with what they act on and their gains (a ``motor``'s
``gear``, a ``position``'s ``kp``, a ``general``'s ``gainprm``/``biasprm``); sensors, tendons,
contact pairs and excludes, keyframes, sites, cameras and lights are grouped by kind (they
carry no dynamics the import leaves out silently); fluid forces (``<option density
viscosity wind>``), gravity compensation (``gravcomp``) and skins are named.
"""
from collections import Counter

__all__ = ["model_notes"]

_GAINS = ("gear", "kp", "kv", "gainprm", "biasprm", "ctrlrange", "forcerange")
_TARGETS = ("joint", "tendon", "site", "body", "jointinparent")


def _counted(kinds):
    return ", ".join(f"{n} {k}" for k, n in sorted(Counter(kinds).items()))


def _actuators(root):
    out = []
    for sec in root.findall("actuator"):
        for el in sec:
            target = next((f"{k} {el.get(k)!r}" for k in _TARGETS if el.get(k)), "nothing named")
            gains = " ".join(f"{k}={el.get(k)}" for k in _GAINS if el.get(k) is not None)
            out.append(f"actuator <{el.tag}> {el.get('name', '(unnamed)')!r} on {target}"
                       + (f" ({gains})" if gains else "") + ": not imported (drive the joint with a library Torque/Force)")
    return out


def _grouped(root, section, what):
    kinds = [el.tag for sec in root.findall(section) for el in sec]
    return [f"{len(kinds)} {what} ({_counted(kinds)}): not imported"] if kinds else []


def _option(root):
    out = []
    for opt in root.findall("option"):
        for k in ("density", "viscosity"):
            if float(opt.get(k, 0.0)) != 0.0:
                out.append(f"<option {k}={opt.get(k)}>: fluid forces not imported")
        if opt.get("wind") and any(float(x) for x in opt.get("wind").split()):
            out.append("<option wind>: not imported")
    return out


def model_notes(root, bodies):
    """The notes of what ``root`` (an MJCF tree, includes spliced) holds that is not imported;
    ``bodies``: the parsed bodies (their sites, cameras, lights and ``gravcomp``)."""
    out = _actuators(root)
    out += _grouped(root, "sensor", "sensors")
    out += _grouped(root, "tendon", "tendons")
    out += _grouped(root, "contact", "contact pairs/excludes")
    out += _grouped(root, "keyframe", "keyframes")
    out += _option(root)
    world = root.find("worldbody")
    kinds = [el.tag for b in [world] + [b.el for b in bodies] for el in b if el.tag in ("site", "camera", "light")]
    if kinds:
        out.append(f"{_counted(kinds)}: not imported (no dynamics)")
    for b in bodies:
        if float(b.el.get("gravcomp", 0.0)) != 0.0:
            out.append(f"body {b.name!r}: gravcomp={b.el.get('gravcomp')} (gravity compensation) not imported")
    for sec in root.findall("deformable") + root.findall("skin"):
        out.append(f"<{sec.tag}>: not imported")
    return out

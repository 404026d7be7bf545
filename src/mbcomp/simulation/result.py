"""Simulation results: named time series, reactions, energies, residuals, statistics.

Variable names are ``<component>.<variable>``:

* joints: coordinates and speeds (``crank.phi``, ``crank.w``; ``slider.s``, ``slider.v``;
  ``ball.Q.w``.., ``ball.w.x``..), reactions ``<joint>.f.x|y|z`` (N) and
  ``<joint>.tau.x|y|z`` (N m): the force and torque exerted on frame_b through the joint,
  resolved in frame_b, torque about frame_b's origin (flange-element forces excluded);
* joints with outputs of their own (:meth:`mbcomp.roles.Joint.outputs`), e.g. rolling
  contacts: ``<contact>.N`` (normal force), ``<contact>.F_long``, ``<contact>.F_lat``;
* drives: ``<drive>.tau`` (rotational) or ``<drive>.f`` (translational), the effort needed to
  impose the motion;
* bodies: ``<body>.r.x|y|z`` (m, origin of frame_a, world), ``<body>.Q.w|x|y|z`` (orientation
  quaternion, frame_a -> world), ``<body>.v.*`` (m/s), ``<body>.w.*`` (rad/s, world);
* ``energy.kinetic``, ``energy.potential``, ``energy.total`` (J);
* ``residual.position`` (norm of Phi, m or 1), ``residual.velocity`` (norm of dPhi/dt),
  ``residual.nonholonomic`` (norm of B u - b);
* model aliases under their alias name.

The columns are computed by :func:`mbcomp.simulation.postprocess.postprocess`.

Examples
--------
>>> import numpy as np
>>> from mbcomp.result import Result
>>> r = Result(np.array([0.0, 1.0]), {"a.phi": np.array([0.0, 2.0])})
>>> float(r["a.phi"][-1])
2.0
"""
from __future__ import annotations

import csv

import numpy as np

__all__ = ["Result"]


class Result:
    """Named time series of one simulation, plus status and statistics.

    Attributes
    ----------
    time : ndarray (n,)
        Output times (s) up to the last accepted step.
    status : {"success", "inaccurate", "failed", "budget", "interrupted"}
        ``"inaccurate"``: the run reached ``t_end`` but a conserved quantity drifted more
        than the tolerances promise (the message gives the drift and a tolerance that fixes
        it; :mod:`mbcomp.simulation.accuracy`); ``"failed"``: the run could not go on (a
        solver failure, a singular position, a component's law that raised); ``"budget"``: the
        wall-time or step budget ran out (``simulate(max_wall_time=, max_steps=)``);
        ``"interrupted"``: Ctrl-C or SIGTERM. Either way the results up to the last accepted
        step are kept.
    message : str
        Why the run ended, and notes (e.g. a contact that pulls); ``"reached t_end"`` and
        notes on success.
    stats : dict
        Solver statistics: steps, nfev, nlu, restarts, projections, cpu_time, method, ...
    summary : str
        The model summary (bodies, DOF, coordinates, constraints).
    events : list of EventRecord
        The run's events in time order: ``(time, component, name, kind, detail)``
        (:class:`mbcomp.hybrid.events.EventRecord`; impacts, stops engaging and releasing,
        the user's event functions).
    units : dict
        ``{column: unit}`` (``"rad"``, ``"N m"``, ``"m/s"``) of the columns whose unit is
        declared (:func:`mbcomp.assembly.column_units.column_units`); others are absent.
    system : MultibodySystem or None
        The assembled system the run integrated, for its scene (:meth:`animate`,
        :meth:`snapshot`); not pickled (a result sent between processes has ``None``).
    """

    def __init__(self, time, series, status="success", message="", stats=None, summary="", units=None,
                 system=None):
        self.time = np.asarray(time)
        self._series = dict(series)
        self.status, self.message = status, message
        self.stats = dict(stats or {})
        self.summary = summary  # a str, or a callable making it at the first read (most runs never read it)
        self.units = dict(units or {})
        self.system = system
        self.events = []  # EventRecord(time, component, name, kind, detail): mbcomp.hybrid.events
        self.sensitivities = None  # SensitivityTable: simulate(..., sensitivities=[...])

    @property
    def summary(self):
        """The model summary (str), made at its first read when the run handed a maker."""
        if callable(self._summary):
            self._summary = self._summary()
        return self._summary

    @summary.setter
    def summary(self, value):
        self._summary = value

    def __getstate__(self):
        self.summary  # made before the system is dropped  # noqa: B018
        state = dict(self.__dict__)
        state["system"] = None  # laws and compiled programs need not pickle; the columns do
        return state

    def animate(self, path=None, hide=(), trails=(), color_by=None, fps=25, speed=1.0, title=None):
        """Write the run as an animation: ``.html`` a self-contained 3-D player (three.js
        inlined; opens offline), ``.gif`` or ``.mp4`` a film through matplotlib's writers;
        with no ``path``, the player to show inline in a notebook.

        Parameters
        ----------
        path : str or os.PathLike, optional
            The file; its suffix picks the kind. ``None``: return an
            :class:`~mbcomp.visual.inline.InlinePlayer`, which a notebook shows as the player
            (``_repr_html_``: the page in an ``<iframe srcdoc=...>``) and ``.save(path)`` writes.
        hide : iterable of str
            Glob patterns of components not drawn (``"*_joint"``).
        trails : iterable of str
            Points whose path is drawn: port paths (``"rod_tip.frame_b"``) or components.
        color_by : dict, optional
            ``{component: column}``: colour by a result column (``"pin.f"``: the magnitude of
            ``pin.f.x|y|z``).
        fps : float
            Frames per second of a film.
        speed : float
            Playback speed (1 = real time).
        title : str, optional

        Returns
        -------
        str or InlinePlayer
            ``path``; the inline player when no path is given.

        Examples
        --------
        >>> import os, tempfile, mbcomp
        >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
        >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
        >>> rod = m.add("rod", FixedTranslation(r=(1, 0, 0))); bob = m.add("bob", PointMass(m=1.0))
        >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
        >>> res = mbcomp.simulate(m, t_end=1.0)
        >>> out = res.animate(os.path.join(tempfile.mkdtemp(), "pendulum.html"), trails=["bob"])
        >>> os.path.getsize(out) < 5e6
        True
        >>> res.animate(trails=["bob"])._repr_html_().startswith("<iframe srcdoc=")  # in a notebook: the player
        True
        """
        if path is None:
            from ..visual.inline import inline_player

            return inline_player(self, hide=hide, trails=trails, color_by=color_by, speed=speed, title=title)
        from ..visual.animation import animate

        return animate(self, path, hide=hide, trails=trails, color_by=color_by, fps=fps, speed=speed, title=title)

    def snapshot(self, path, t=None, hide=(), trails=(), color_by=None, title=None):
        """Write one frame at time ``t`` (s; the last output by default) as a picture
        (``.png``, ``.svg``, ``.pdf``), drawn with matplotlib's 3-D axes.

        Examples
        --------
        >>> import os, tempfile, mbcomp
        >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
        >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
        >>> rod = m.add("rod", FixedTranslation(r=(1, 0, 0))); bob = m.add("bob", PointMass(m=1.0))
        >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
        >>> res = mbcomp.simulate(m, t_end=1.0)
        >>> os.path.exists(res.snapshot(os.path.join(tempfile.mkdtemp(), "t1.png"), t=1.0))
        True
        """
        from ..visual.animation import snapshot

        return snapshot(self, path, t=t, hide=hide, trails=trails, color_by=color_by, title=title)

    @property
    def names(self):
        """Every variable name, in CSV column order (after ``time``)."""
        return list(self._series)

    def sensitivity(self, column, param):
        """``d column / d param`` at the output times (column's unit per parameter's unit).

        Parameters
        ----------
        column : str
            A result column: a coordinate or speed (``"crank_joint.phi"``, an alias such as
            ``"crank_angle"``), or any column of the output program (reactions
            ``"pin.f.x"``, ``"energy.total"``, body poses and twists, joints' outputs).
        param : str
            A parameter named in ``simulate(..., sensitivities=[...])``.

        Returns
        -------
        ndarray (n_out,)
            The derivative at each output time; NaN after ``res.sensitivities.stopped``.

        Raises
        ------
        KeyError
            The run was made without ``sensitivities=``, ``param`` was not asked, or
            ``column`` has no sensitivity (the message names what there is).

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
        >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
        >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> r = mbcomp.simulate(m, t_end=1.0, n_out=2, sensitivities=["b.m"])
        >>> # free fall: the motion has no mass in it; V = -m g.r, so dV/dm = V/m
        >>> float(r.sensitivity("s.s", "b.m")[-1]), round(float(r.sensitivity("energy.potential", "b.m")[-1]), 5)
        (0.0, -48.11805)
        """
        if self.sensitivities is None:
            raise KeyError("this run has no sensitivities -> simulate(..., sensitivities=['component.param', ...])")
        return self.sensitivities.of(column, param)

    def __getitem__(self, name):
        if name == "time":
            return self.time
        try:
            return self._series[name]
        except KeyError:
            close = [n for n in self._series if name.split(".")[0] in n][:8]
            raise KeyError(f"no variable {name!r} in the result; similar: {', '.join(close) or 'none'} "
                           f"(see Result.names)") from None

    def __contains__(self, name):
        return name == "time" or name in self._series

    def set_column(self, name, values, unit=None):
        """Add or replace the column ``name`` (one value per output time; ``unit``: its unit)."""
        self._series[name] = values
        if unit is not None:
            self.units[name] = unit

    @property
    def success(self):
        return self.status == "success"

    def to_csv(self, path, units=False):
        """Write ``time`` and every variable as columns to ``path``; with ``units``, headers
        ``name [unit]`` for the columns whose unit is known (:attr:`units`).

        Examples
        --------
        >>> import numpy as np, os, pathlib, tempfile
        >>> from mbcomp.result import Result
        >>> r = Result(np.array([0.0, 1.0]), {"a.phi": np.array([0.0, 2.0])}, units={"a.phi": "rad"})
        >>> path = r.to_csv(os.path.join(tempfile.mkdtemp(), "r.csv"), units=True)
        >>> pathlib.Path(path).read_text().splitlines()[0]
        'time [s],a.phi [rad]'
        """
        names = self.names

        def head(n, u):
            return f"{n} [{u}]" if units and u else n
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([head("time", "s")] + [head(n, self.units.get(n)) for n in names])
            cols = [self.time] + [self._series[n] for n in names]
            for row in zip(*cols):
                w.writerow([f"{x:.12g}" for x in row])
        return path

    def to_dataframe(self, columns=None):
        """The run as a ``pandas.DataFrame``: index ``time`` (s), one column per result column;
        units in ``df.attrs["units"]`` (``{column: unit}``, ``"time": "s"``), and ``status``,
        ``message``, ``stats``, ``events`` in ``df.attrs``
        (:func:`mbcomp.simulation.result_tables.to_dataframe`). Needs pandas
        (``pip install mbcomp[data]``).

        Parameters
        ----------
        columns : list of str, optional
            The columns to keep (default: all); a name that is no column is a ``KeyError``.

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp.result import Result
        >>> r = Result(np.array([0.0, 1.0]), {"j.phi": np.array([0.0, 2.0])}, units={"j.phi": "rad"})
        >>> df = r.to_dataframe()
        >>> float(df.loc[1.0, "j.phi"]), df.attrs["units"]["j.phi"], df.attrs["status"]
        (2.0, 'rad', 'success')
        """
        from .result_tables import to_dataframe

        return to_dataframe(self, columns)

    def to_xarray(self, columns=None):
        """The run as an ``xarray.Dataset``: dimension ``time`` (s), each column a variable with
        ``attrs["units"]``; the run's ``status``, ``message``, ``stats.<name>`` and ``events``
        in the Dataset's attrs (:func:`mbcomp.simulation.result_tables.to_xarray`). Needs
        xarray (``pip install mbcomp[data]``).

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp.result import Result
        >>> ds = Result(np.array([0.0, 1.0]), {"j.phi": np.array([0.0, 2.0])}, units={"j.phi": "rad"}).to_xarray()
        >>> ds["j.phi"].attrs["units"], ds.attrs["status"], ds.sizes["time"]
        ('rad', 'success', 2)
        """
        from .result_tables import to_xarray

        return to_xarray(self, columns)

    def to_mat(self, path, columns=None):
        """Write the run as a Modelica result file (the MAT v4 layout OpenModelica and Dymola
        write: ``Aclass``, ``name``, ``description``, ``dataInfo``, ``data_1``, ``data_2``), which
        OMEdit, DyMat and OMPython read (:mod:`mbcomp.simulation.modelica_mat`). Columns constant
        over the run go to ``data_1``, the others to ``data_2``; each description ends with the
        column's unit in brackets. Returns ``path``.

        Examples
        --------
        >>> import numpy as np, os, tempfile, scipy.io
        >>> from mbcomp.result import Result
        >>> r = Result(np.array([0.0, 1.0]), {"j.phi": np.array([0.0, 2.0])}, units={"j.phi": "rad"})
        >>> f = scipy.io.loadmat(r.to_mat(os.path.join(tempfile.mkdtemp(), "r.mat")))
        >>> f["data_2"].tolist()
        [[0.0, 1.0], [0.0, 2.0]]
        """
        from .modelica_mat import write_mat

        return write_mat(self, path, columns)

    def _repr_html_(self):
        """The run's summary in a notebook: status, statistics, the first and last rows of a
        few columns, the events (:func:`mbcomp.simulation.result_html.result_html`)."""
        from .result_html import result_html

        return result_html(self)

    def plot(self, patterns=None, path=None, title=None):
        """Plot columns against time, one panel each; save to ``path`` (PNG) if given.

        Parameters
        ----------
        patterns : str or list of str, optional
            Column names or shell-style globs (``"crank.*"``, ``"*.tau.z"``); default
            :meth:`default_plot_names`. A pattern matching nothing is a ``ValueError``
            listing similar names (:func:`mbcomp.simulation.plotting.select`).
        path, title : str, optional

        Returns
        -------
        matplotlib.figure.Figure

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp.result import Result
        >>> r = Result([0.0, 1.0], {"a.phi": np.zeros(2), "a.tau.z": np.ones(2), "b.tau.z": np.ones(2)})
        >>> fig = r.plot("*.tau.z")
        >>> [ax.get_ylabel() for ax in fig.axes]
        ['a.tau.z', 'b.tau.z']
        >>> import matplotlib.pyplot as plt; plt.close(fig)
        """
        from .plotting import draw, select

        names = select(self.names, patterns) if patterns else self.default_plot_names()
        return draw(self, names, path, title)

    def default_plot_names(self):
        """The columns a user looks at first: coordinates (a joint's angular speeds instead of
        its quaternion), ``energy.balance`` or ``energy.total``, and the constraint residuals
        of a model with loops (:func:`mbcomp.simulation.plotting.default_names`)."""
        from .plotting import default_names

        return default_names(self)

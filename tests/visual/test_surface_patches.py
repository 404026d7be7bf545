"""Curved surfaces drawn: each surface's translucent patch (an inline ``Mesh``) lies on the
surface, and in a run the ball's centre stays at distance ``r`` from the drawn patch.

* every vertex of each surface's patch has signed distance ``G = 0`` (the surface's own
  ``distance``) to 1e-12 m, with and without a track of the ball's centre;
* the patch covers the track: the bowl's cap reaches past the widest angle the ball went to,
  the half-pipe spans the track along its axis;
* a ball rolling in a bowl and across a half-pipe: the drawn mesh, placed in the world by the
  scene, is the sphere (cylinder) of the surface (least-squares fit of its vertices), the
  ball's centre stays at ``R - r`` from its centre (axis), and no vertex comes nearer to the
  centre than ``r``;
* ``Mesh(vertices=, faces=)`` checks its arrays and ``Mesh.from_grid`` leaves out cells with
  an undefined corner.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import FreeMotion, RigidBody, SphereContact, World
from mbcomp.library.surfaces import CylinderSurface, HeightField, Plane, SphereSurface, TorusSurface
from mbcomp.modeling.shapes import Grid, Mesh
from mbcomp.visual.scene import build_scene, mesh_triangles

R_BALL = 0.1


class View:
    """A stand-in for the scene's view: a scale and, optionally, the ball's track."""

    def __init__(self, scale=1.0, track=None):
        self.scale, self._track = scale, track

    def track(self, port, of):
        assert (port, of) == ("frame_a", "frame_b")
        return self._track


def wavy(x, y):
    return 0.3 * (x * x - 0.5 * y * y) + 0.05 * np.sin(2.0 * x) * np.cos(y)


SURFACES = {
    "bowl": SphereSurface(R=1.2, center=(0.1, 0, 1.0)),
    "tilted bowl": SphereSurface(R=1.0, center=(0, 0, 0), pole=(0, 1, 1)),
    "dome": SphereSurface(R=0.8, inside=False),
    "pipe": CylinderSurface(R=1.0, axis=(1, 0.2, 0), center=(0, 0, 1.0)),
    "rod": CylinderSurface(R=0.3, axis=(0, 0, 1), inside=False),
    "tube": TorusSurface(R=2.0, a=0.5, inside=True),
    "ring": TorusSurface(R=2.0, a=0.5, axis=(0, 0.3, 1), inside=False),
    "cap": HeightField(lambda x, y: 1.5 - np.sqrt(1.5 ** 2 - x * x - y * y)),
    "wavy": HeightField(wavy),
}


def vertices_of(surface, view):
    (mesh,) = surface.visuals(R_BALL, view)
    assert isinstance(mesh, Mesh) and mesh.inline and mesh.frame == "frame_a" and mesh.opacity < 1
    return mesh.triangles()


@pytest.mark.parametrize("name", SURFACES)
@pytest.mark.parametrize("with_track", [False, True])
def test_patch_vertices_lie_on_the_surface(name, with_track):
    surface = SURFACES[name]
    track = None
    if with_track:  # a short path near the bottom / on the surface, offset by the ball's radius
        pts, _ = vertices_of(surface, View(1.0))
        track = pts[:: max(1, len(pts) // 7)][:5] + 0.0
    V, F = vertices_of(surface, View(1.0, track))
    G = np.array([surface.distance(v)[0] for v in V])
    assert np.max(np.abs(G)) < 1e-12, f"{name}: a vertex is {np.max(np.abs(G)):.2g} m off the surface"
    assert F.min() >= 0 and F.max() < len(V) and len(F) >= len(V)  # a real triangulation


def test_bowl_cap_reaches_past_the_track():
    bowl = SphereSurface(R=1.0, center=(0, 0, 1.0))
    V0, _ = vertices_of(bowl, View())
    angle = lambda V: np.degrees(np.arccos(np.clip((np.array([0, 0, 1.0]) - V) @ (0, 0, 1), -1, 1)))  # noqa: E731
    assert abs(angle(V0).max() - 60.0) < 1e-9  # without a run: a cap of half-angle 60 degrees
    th = np.radians(75.0)  # a ball centre that went 75 degrees up the wall
    track = np.array([[0, 0, 1.0 - 0.9], [0.9 * np.sin(th), 0, 1.0 - 0.9 * np.cos(th)]])
    V, _ = vertices_of(bowl, View(track=track))
    assert angle(V).max() > 75.0 + np.degrees(R_BALL / 1.0)


def test_half_pipe_spans_the_track_along_its_axis():
    pipe = CylinderSurface(R=1.0, axis=(1, 0, 0), center=(0, 0, 1.0))
    track = np.array([[-2.0, 0, 0.1], [3.0, 0.0, 0.1]])
    V, _ = vertices_of(pipe, View(scale=1.0, track=track))
    assert V[:, 0].min() <= -2.0 - 3 * R_BALL + 1e-12 and V[:, 0].max() >= 3.0 + 3 * R_BALL - 1e-12
    assert V[:, 2].max() <= 1.0 + 1e-12  # the lower half only: the ball went along the bottom
    assert abs(V[:, 2].min()) < 1e-12  # and the bottom line is in it


def test_plane_is_a_grid_and_meshes_check_their_arrays():
    (grid,) = Plane(n=(0, 0, 1), origin=(0, 0, 0.5)).visuals(R_BALL, View())
    assert isinstance(grid, Grid) and grid.r == (0.0, 0.0, 0.5) and not grid.floor
    with pytest.raises(ValueError, match="faces= must be an"):
        Mesh(vertices=[(0, 0, 0), (1, 0, 0), (0, 1, 0)], faces=[(0, 1, 3)])
    with pytest.raises(ValueError, match="vertices= must be an"):
        Mesh(vertices=[(0, 0)], faces=[(0, 0, 0)])
    with pytest.raises(ValueError, match="either a path or"):
        Mesh("a.stl", vertices=[(0, 0, 0)] * 3, faces=[(0, 1, 2)])
    P = np.zeros((3, 3, 3))
    P[..., 0], P[..., 1] = np.meshgrid(np.arange(3.0), np.arange(3.0), indexing="ij")
    P[2, 2, 2] = np.nan  # one undefined corner: its one cell (two triangles) and the point dropped
    m = Mesh.from_grid(P)
    assert (len(m.vertices), len(m.faces)) == (8, 6)


# --------------------------------------------------------------------------- in a run

def ball_on(surface, c0, v0):
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -9.81)))
    free = mdl.add("free", FreeMotion(r0=c0, v0=v0))
    ball = mdl.add("ball", RigidBody(m=0.5, I=0.4 * 0.5 * R_BALL**2 * np.eye(3)))
    c = mdl.add("contact", SphereContact(r=R_BALL, surface=surface))
    mdl.connect(w.frame_b, free.frame_a)
    mdl.connect(free.frame_b, ball.frame_a)
    mdl.connect(w.frame_b, c.frame_a)
    mdl.connect(c.frame_b, ball.frame_a)
    return mdl


def drawn_surface(res):
    """The surface patch's vertices placed in the world by the scene (m), and the ball's centres."""
    scene = build_scene(res)
    (patch,) = [v for v in scene.visuals if v.component == "contact" and isinstance(v.shape, Mesh)]
    V, _ = mesh_triangles(patch.shape)
    R, r = scene.placement(patch, 0)
    k = [i for i, link in enumerate(scene.links) if link.name == "ball"][0]
    centres = np.array([scene.point(k, (0, 0, 0), j) for j in range(len(scene.time))])
    return V @ R.T + r, centres


def test_ball_in_a_bowl_stays_r_from_the_drawn_bowl():
    R = 1.0
    th = 0.5  # start 0.5 rad up the wall, moving sideways: the ball circles and swings
    c0 = (0.0, 0.0, R) + (R - R_BALL) * np.array([np.sin(th), 0.0, -np.cos(th)])
    res = mbcomp.simulate(ball_on(SphereSurface(R=R, center=(0, 0, R)), c0, (0, 0.8, 0)), t_end=2.0, n_out=60,
                          rtol=1e-10, atol=1e-12)
    W, C = drawn_surface(res)
    # the drawn vertices are the sphere: fit |x|^2 = 2 x.c + (R^2 - |c|^2)
    A = np.column_stack([2 * W, np.ones(len(W))])
    sol = np.linalg.lstsq(A, (W * W).sum(axis=1), rcond=None)[0]
    centre, radius = sol[:3], np.sqrt(sol[3] + sol[:3] @ sol[:3])
    assert np.allclose(centre, (0, 0, R), atol=1e-6) and abs(radius - R) < 1e-6
    np.testing.assert_allclose(np.linalg.norm(C - centre, axis=1), R - R_BALL, atol=1e-6)
    nearest = np.min(np.linalg.norm(C[:, None, :] - W[None, :, :], axis=2), axis=1)
    assert nearest.min() >= R_BALL - 1e-6  # no drawn vertex inside the ball
    assert nearest.max() < R_BALL + 0.05 * R  # and the patch is under the ball all the way (grid spacing)


def test_ball_across_a_half_pipe_stays_r_from_the_drawn_pipe():
    R = 1.0
    th = 0.4
    c0 = (0.0, 0.0, R) + (R - R_BALL) * np.array([0.0, np.sin(th), -np.cos(th)])
    res = mbcomp.simulate(ball_on(CylinderSurface(R=R, axis=(1, 0, 0), center=(0, 0, R)), c0, (0.5, 0, 0)),
                          t_end=2.0, n_out=60, rtol=1e-10, atol=1e-12)
    W, C = drawn_surface(res)
    assert np.allclose(np.hypot(W[:, 1], W[:, 2] - R), R, atol=1e-6)  # the drawn pipe is the surface
    np.testing.assert_allclose(np.hypot(C[:, 1], C[:, 2] - R), R - R_BALL, atol=1e-6)
    assert W[:, 0].min() < C[:, 0].min() and W[:, 0].max() > C[:, 0].max()  # it covers the ball's travel
    nearest = np.min(np.linalg.norm(C[:, None, :] - W[None, :, :], axis=2), axis=1)
    assert nearest.min() >= R_BALL - 1e-6 and nearest.max() < R_BALL + 0.1 * R

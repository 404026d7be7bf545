"""
A closed loop: the parallelogram four-bar
=========================================

Mechanisms with loops are modelled as you would draw them: connect every joint, and mbcomp
finds a spanning tree, *cuts* one joint of each loop and keeps its rows as constraints with
Lagrange multipliers. Here a parallelogram: crank and rocker of length :math:`L` on ground
pivots :math:`D` apart, joined by a coupler of length :math:`D`. Of the cut hinge's five rows
(it is a 3-D revolute joint) three are redundant in a planar loop: mbcomp drops them and says
so (``mbcomp.assemble(model).summary()``, or ``mbcomp info`` on a model file).

The loop forces the rocker to turn with the crank and keeps the coupler level; the crank obeys
:math:`(\\tfrac23 m L^2 + m_c L^2)\\ddot\\varphi = -g(m L + m_c L)\\cos\\varphi`. The kept
rows' multipliers are the force the cut joint transmits (``lambda.<joint>.x``, ``.y``, N): by
symmetry crank and rocker carry the same load, so it equals the crank pivot's force
(``crank_joint.f.*``, a tree joint's reaction output) in size.

At :math:`\\varphi = 0` and :math:`\\pi` the parallelogram lies flat, every link on the ground
line: the loop's Jacobian loses rank there and a run stops, naming the position (the N-four-bar
example passes such positions with ``singular="pass"``). Released 0.6 rad from hanging down,
this one swings below them.
"""
import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp import Guess
from mbcomp.library import Fixed, FixedTranslation, Revolute, RigidBody, World

L, D, m, mc, g, phi0 = 0.5, 1.0, 1.0, 2.0, 9.81, -np.pi / 2 + 0.6   # 0.6 rad from hanging down


def rod(mass, length):
    """A uniform rod along its frame's x axis (inertia about its centre, kg m^2)."""
    I = mass * length ** 2 / 12
    return RigidBody(m=mass, r_cm=(length / 2, 0, 0), I=np.diag([0.0, I, I]))


model = mbcomp.Model()
world = model.add("world", World(g=(0, -g, 0)))
pivot = model.add("pivot", Fixed(r=(D, 0, 0)))
crank_joint = model.add("crank_joint", Revolute(n=(0, 0, 1), phi0=phi0))
crank = model.add("crank", rod(m, L))
crank_tip = model.add("crank_tip", FixedTranslation(r=(L, 0, 0)))
coupler_joint = model.add("coupler_joint", Revolute(n=(0, 0, 1), phi0=Guess(-phi0)))
coupler = model.add("coupler", rod(mc, D))
coupler_tip = model.add("coupler_tip", FixedTranslation(r=(D, 0, 0)))
rocker_joint = model.add("rocker_joint", Revolute(n=(0, 0, 1), phi0=Guess(phi0)))
rocker = model.add("rocker", rod(m, L))
rocker_tip = model.add("rocker_tip", FixedTranslation(r=(L, 0, 0)))
pin = model.add("pin", Revolute(n=(0, 0, 1), phi0=Guess(0.0)))
for a, b in [(world.frame_b, crank_joint.frame_a), (crank_joint.frame_b, crank.frame_a),
             (crank_joint.frame_b, crank_tip.frame_a), (crank_tip.frame_b, coupler_joint.frame_a),
             (coupler_joint.frame_b, coupler.frame_a), (coupler_joint.frame_b, coupler_tip.frame_a),
             (pivot.frame_b, rocker_joint.frame_a), (rocker_joint.frame_b, rocker.frame_a),
             (rocker_joint.frame_b, rocker_tip.frame_a),
             (coupler_tip.frame_b, pin.frame_a), (rocker_tip.frame_b, pin.frame_b)]:   # the last closes the loop
    model.connect(a, b)

system = mbcomp.assemble(model)
print(system.summary())
res = mbcomp.simulate(model, t_end=2.0, rtol=1e-10, atol=1e-12, n_out=201)

# %%
# The crank against the one-degree-of-freedom equation, the loop residual, and the loop's
# reactions: the multipliers of the cut joint's kept rows (``lambda.*``, N).
J, G = 2 / 3 * m * L ** 2 + mc * L ** 2, g * (m * L + mc * L)
ref = solve_ivp(lambda t, y: [y[1], -G * np.cos(y[0]) / J], (0, 2.0), [phi0, 0.0], t_eval=res.time,
                method="DOP853", rtol=1e-11, atol=1e-12)
fig, axs = plt.subplots(3, 1, layout="constrained", figsize=(6, 5), sharex=True)
axs[0].plot(res.time, res["crank_joint.phi"], label="crank")
axs[0].plot(res.time, res["rocker_joint.phi"], ":", label="rocker")
axs[0].plot(res.time, ref.y[0], "--", label="one-DOF equation")
axs[0].set_ylabel("angle (rad)")
axs[0].legend(fontsize=8)
axs[1].semilogy(res.time, np.maximum(res["residual.position"], 1e-17))
axs[1].set_ylabel("loop residual (m)")
lam = [n for n in res.names if n.startswith("lambda.")]
for name in lam:
    axs[2].plot(res.time, res[name], label=name)
crank_force = np.sqrt(sum(res[f"crank_joint.f.{c}"] ** 2 for c in "xyz"))
axs[2].plot(res.time, crank_force, "--", label="|crank pivot force|")
axs[2].set_ylabel("reaction (N)")
axs[2].set_xlabel("t (s)")
axs[2].legend(fontsize=8)
plt.show()

# %%
# The check: the rocker turns with the crank, the crank follows the equation, the loop stays
# closed, and the loop's force is the crank pivot's in size.
CHECKS = {"max |rocker - crank| (rad)": (np.max(np.abs(res["rocker_joint.phi"] - res["crank_joint.phi"])), 1e-8),
          "max |crank - one-DOF equation| (rad)": (np.max(np.abs(res["crank_joint.phi"] - ref.y[0])), 1e-7),
          "max loop residual (m)": (np.max(res["residual.position"]), 1e-9),
          "max ||lambda| - |crank pivot force|| (N)": (np.max(np.abs(np.sqrt(sum(res[n] ** 2 for n in lam)) - crank_force)), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name

"""Algorithm 1's step written again from the paper's equations, one user at a time, in plain NumPy.

The independent reference that the live station (tests/test_teleop.py) and the latent map's
held inputs (tests/test_latent_map.py) are checked against. Nothing here calls lasa's step,
belief, blend, assistance or safety code; it reads only the decoder under test (phi), the
task's data (goals, goal sets, joint limits) and the control units, and follows the formulas
as lasa/method/belief.py and blend.py state them:

- the human action a_h = phi(z, s, b), or nothing for a stick at rest under ``rest="zero"``;
- the assistance, blend weight 1: Eq. M2 (the ``point`` member), a_r = sum_g b(g) (g - s), or
  ``hindsight``, a_r = sigma_h sum_g b(g) (c_g - s) / max(||c_g - s||, dt sigma_h), c_g the point of
  goal g's set (its ``preference_sets`` polyline) nearest to s (``hindsight_point``: c_g = g);
- Eq. M1: a = (1 - alpha) a_h + alpha a_r;
- the belief: b'(g) proportional to b(g) exp(-beta_b regret_g), regret_g = d_g(s + dt a_h) - d_g(s)
  (+ min(dt sigma_h, d_g(s)) under the ``preferences`` likelihood), d_g the distance to goal g's
  polyline; then every goal keeps at least the floor f: b' <- (1 - G f) b' + f;
- the transition s' = clip(s + dt clip(a, -v, v), lower, upper), v the joint speed bound.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np


def softmax(log_b: np.ndarray) -> np.ndarray:
    """b from log b, shape (G,)."""
    w = np.exp(log_b - log_b.max())
    return w / w.sum()


def nearest_on_polyline(point: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """The point of the polyline through ``polyline``'s K rows nearest to ``point`` (n,) (K = 1: a point)."""
    if len(polyline) == 1:
        return polyline[0]
    best, nearest = math.inf, polyline[0]
    for a, b in zip(polyline[:-1], polyline[1:], strict=True):
        ab = b - a
        t = min(max(float((point - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0), 1.0)
        if math.dist(point, a + t * ab) < best:
            best, nearest = math.dist(point, a + t * ab), a + t * ab
    return nearest


def polyline_distance(point: np.ndarray, polyline: np.ndarray) -> float:
    """Distance from ``point`` (n,) to the polyline through ``polyline``'s K rows (K = 1: a point)."""
    return math.dist(point, nearest_on_polyline(point, polyline))


def belief_update(
    b: np.ndarray, s: np.ndarray, a_h: np.ndarray, goal_sets: np.ndarray, control
) -> np.ndarray:
    """b' after the human action ``a_h`` at ``s``; ``sets`` (G, K, n) are the goals' polylines."""
    moved = s + control.dt * a_h
    regret = np.empty(len(b))
    for g, polyline in enumerate(goal_sets):
        before, after = polyline_distance(s, polyline), polyline_distance(moved, polyline)
        regret[g] = after - before
        if control.likelihood == "preferences":
            regret[g] += min(control.dt * control.action_scale, before)
    post = b * np.exp(-control.belief_beta * (regret - regret.min()))
    post = post / post.sum()
    post = (1.0 - len(b) * control.belief_floor) * post + control.belief_floor
    cap = getattr(control, "belief_cap", None)
    if cap is not None:
        post = capped(post, cap)
    return post


def capped(b: np.ndarray, cap: float) -> np.ndarray:
    """Javdani et al.'s clip in probabilities, goal by goal: the top above ``cap`` is set to it and
    its excess is shared equally by the others."""
    out = [float(x) for x in b]
    top = max(range(len(out)), key=lambda g: out[g])
    if out[top] > cap:
        share = (out[top] - cap) / (len(out) - 1)
        out = [cap if g == top else x + share for g, x in enumerate(out)]
    return np.array(out)


def transition(s: np.ndarray, a: np.ndarray, control, robot) -> np.ndarray:
    """s' from s and the commanded action ``a``: the speed bound, then the joint limits."""
    velocity = np.clip(a, -control.max_joint_speed, control.max_joint_speed)
    return np.clip(s + control.dt * velocity, robot.lower, robot.upper)


def assistance(member: str, b: np.ndarray, s: np.ndarray, task, control) -> np.ndarray:
    """a_r of the member ``point`` (Eq. M2), ``hindsight`` or ``hindsight_point``, shape (n,)."""
    a_r = np.zeros(len(s))
    sets = task.preference_sets  # the members' goal sets (lasa.method.step)
    for weight, goal, polyline in zip(b, task.goals, sets, strict=True):
        if member == "point":
            a_r += weight * (goal - s)
        elif member in ("hindsight", "hindsight_point"):
            target = nearest_on_polyline(s, polyline) if member == "hindsight" else goal
            reach = max(math.dist(target, s), control.dt * control.action_scale)
            a_r += control.action_scale * weight * (target - s) / reach
        else:
            raise NotImplementedError(
                f"the reference writes out 'point' and the hindsight ones, not {member!r}"
            )
    return a_r


def step_with(task, control, s: np.ndarray, b: np.ndarray, a_h: np.ndarray, alpha: float) -> dict:
    """Lines 6-9 of Algorithm 1 for one user, given the human action: a_r, a, s' and b'."""
    a_r = assistance(control.assistance, b, s, task, control)
    a = (1.0 - alpha) * a_h + alpha * a_r
    goal_sets = task.goals[:, None, :] if control.likelihood == "goal" else task.preference_sets
    return {
        "a_h": a_h,
        "a_r": a_r,
        "a": a,
        "s": transition(s, a, control, task.robot),
        "b": belief_update(b, s, a_h, goal_sets, control),
    }


def latent_step(decoder, task, control, s, b, z, alpha: float, rest: str = "decode") -> dict:
    """One step of latent actions for one user: phi decodes the stick, then :func:`step_with`."""
    z = np.asarray(z, dtype=float)
    if rest == "zero" and not np.any(z):
        a_h = np.zeros(len(s))
    else:
        a_h = decoder.decode_numpy(z[None], s[None], b[None])[0]
    return step_with(task, control, s, b, a_h, alpha)


def site_frame(robot, q):
    """The grasp site's position, rotation and (translation over rotation) Jacobian, by MuJoCo
    itself (mj_jacSite) at joints ``q``: not lasa's chain kinematics."""
    m, d = robot.model, mujoco.MjData(robot.model)
    d.qpos[robot.qpos_adr] = q
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    site = m.site(robot.spec.grasp_site).id
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jacp, jacr, site)
    dofs = [m.jnt_dofadr[m.joint(j).id] for j in robot.spec.joints]
    return d.site_xpos[site].copy(), d.site_xmat[site].reshape(3, 3).copy(), np.vstack([jacp, jacr])[:, dofs]

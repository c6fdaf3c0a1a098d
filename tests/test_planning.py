"""Planning participants: the one-step study's record, timing of holds, and a detour they find."""

import dataclasses

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_array_equal
from stand_ins import LinearDecoder

from lasa.base.errors import ConfigError
from lasa.people import participants, planning
from lasa.people.cohort import draw_cohort
from lasa.people.design import StudyConfig
from lasa.people.planning import PlanConfig
from lasa.people.policy import progress_gain
from lasa.world.eating import GOALS, PREFERENCES, fork_frame, make_eating_task
from lasa.world.fork import tip_frames, tip_motion

FIELDS = ("states", "tip", "direction", "phase", "idle", "switch", "end", "completed", "belief", "waypoint")


class DetourDecoder:
    """Pushing stick axis 1 forward (z1 > 0) drives the arm along a detour to a target pose q*.

    First along a straight leg to a via point that moves the fork away from its waypoint,
    then straight to q*; the leg is chosen by how far the state has come along q* - start
    (monotone along both legs), so the field needs no memory. Any other input does nothing.
    """

    robot, n_goals, z_dim = "panda", 4, 2

    def __init__(
        self, start: np.ndarray, target: np.ndarray, via: np.ndarray, speed: float, dt: float
    ) -> None:
        self.start, self.target, self.speed, self.dt = start, target, speed, dt
        self.forward = (target - start) / np.linalg.norm(target - start)
        self.leg = (via - start) / np.linalg.norm(via - start)
        self.switch = float((via - start) @ self.forward)

    def decode_numpy(self, z, s, b):
        shape = np.broadcast_shapes(z.shape[:-1], s.shape[:-1], b.shape[:-1])
        s = np.broadcast_to(s, (*shape, 7))
        push = np.clip(np.broadcast_to(np.asarray(z)[..., 0], shape), 0.0, 1.0)
        to_target = self.target - s
        dist = np.linalg.norm(to_target, axis=-1, keepdims=True)
        home = to_target / np.maximum(dist, 1e-12) * np.minimum(1.0, dist / (self.speed * self.dt))
        first = ((s - self.start) @ self.forward < self.switch)[..., None]
        return push[..., None] * self.speed * np.where(first, self.leg, home)


@pytest.fixture(scope="module")
def eating():
    return make_eating_task()


def _run(module, eating, decoder=None, n=2, horizon=30, interfaces=("R", "LA"), **kw):
    return module.simulate(
        eating,
        decoder or LinearDecoder(),
        draw_cohort(n, seed=1),
        eating.robot.control,
        StudyConfig(horizon=horizon),
        seed=2,
        progress=False,
        interfaces=interfaces,
        **kw,
    )


@pytest.fixture(scope="module")
def small(eating):
    return _run(planning, eating)


def test_the_planned_roll_of_a_latent_input_is_the_reference_step_held(eating):
    """The plan foresees a latent input by holding it through Algorithm 1's step: with every rolled
    step exact (``coarse = 1``), each hold's end is the independent reference step applied h times."""
    from reference_step import latent_step, softmax

    from lasa.people.simulation import prepare

    plan = PlanConfig(replan=0.5, holds=(0.1, 0.5, 1.0), coarse=1)
    config = StudyConfig(horizon=30)
    setting = prepare(
        eating, LinearDecoder(), draw_cohort(1, seed=1), eating.robot.control, config, 2, ("LA",)
    )
    study = planning._prepare(setting, plan)
    idx = np.flatnonzero(study.layout.alpha > 0)[:1]  # one LA+SA episode: assistance in the roll
    n, g = eating.robot.n_joints, eating.n_goals
    state = eating.start[None] + 0.01
    log_b = np.log(np.array([[0.4, 0.3, 0.2, 0.1]]))
    snaps = planning._rollout_states(study, idx, state, log_b)  # (1, K', H, n)
    control = dataclasses.replace(eating.robot.control, assistance=str(study.layout.assistance_run[idx[0]]))
    alpha = float(study.layout.alpha[idx[0]])
    for m in (0, 7, len(study.moves) - 1):
        z = study.grid[study.moves[m]]
        s, b = state[0].copy(), softmax(log_b[0])
        for step in range(1, int(study.hold_steps[-1]) + 1):
            out = latent_step(study.decoder, eating, control, s, b, z, alpha, "zero")
            s, b = out["s"], out["b"]
            for h in np.flatnonzero(study.hold_steps == step):
                np.testing.assert_allclose(snaps[0, m, h], s, atol=1e-9)
    assert alpha > 0 and snaps.shape == (1, len(study.moves), 3, n) and g == 4


def test_a_planning_record_keeps_the_study_invariants(eating, small):
    """Same episodes as the one-step study, states held after each episode's end, no input recorded
    after it, phases that only move forward, and completion exactly when the end is before the horizon."""
    one_step = _run(participants, eating)
    for name in ("participant", "condition", "assistance", "task", "order"):
        assert_array_equal(getattr(small, name), getattr(one_step, name))
    horizon = small.idle.shape[0]
    for e, end in enumerate(small.end):
        assert_array_equal(
            small.states[end:, e], np.broadcast_to(small.states[end, e], small.states[end:, e].shape)
        )
        assert not small.switch[end:, e].any()
        assert np.all(np.diff(small.phase[: end + 1, e]) >= 0)
    assert_array_equal(small.completed, small.end < horizon)
    assert small.idle[: small.end.max()].any()  # some participant rested while running


def test_deterministic(eating, small):
    again = _run(planning, eating)
    for name in FIELDS:
        assert_array_equal(getattr(small, name), getattr(again, name))


def test_a_participant_does_not_depend_on_the_cohort_size(eating, small):
    alone = _run(planning, eating, n=1)
    cols = small.participant == 0
    for name in FIELDS:
        ours, theirs = getattr(small, name), getattr(alone, name)
        assert_array_equal(ours[..., cols, :] if ours.ndim == 3 else ours[..., cols], theirs, err_msg=name)


def test_an_input_held_at_least_a_replan_is_constant_until_the_next_replan(eating):
    # phi = z W does not depend on the state: a latent-action step reveals the input held
    ep = _run(planning, eating, LinearDecoder(scale=0.05), n=1, horizon=40, interfaces=("LA",),
              plan=PlanConfig(holds=(0.5, 1.0)))  # fmt: skip
    cols = np.flatnonzero(ep.condition == "LA")
    steps = np.diff(ep.states[:, cols], axis=0)[:40].reshape(8, 5, len(cols), 7)  # blocks of 0.5 s
    assert np.allclose(steps, steps[:, :1], atol=1e-12)
    assert np.all(ep.idle[:40, cols].reshape(8, 5, -1) == ep.idle[:40:5, cols][:, None])
    assert (~ep.idle[:, cols]).any()  # the participant does push


def test_a_tap_is_followed_by_rest_until_the_replan(eating):
    ep = _run(planning, eating, LinearDecoder(scale=0.05), n=1, horizon=20, plan=PlanConfig(holds=(0.1,)))
    phase = np.arange(20) % 5
    la = np.char.startswith(ep.condition.astype(str), "LA")
    assert ep.idle[phase != 0][:, la].all()  # a tap, then the stick rests
    assert ep.idle[phase >= 3].all()  # Retargeting: up to two presses and the tap first
    assert (~ep.idle[phase == 0]).any()


@pytest.fixture(scope="module")
def detour(eating):
    """A decoder whose pushes first lead away from the first waypoint, then to it."""
    robot, control = eating.robot, eating.robot.control
    stab = PREFERENCES["stab"]
    target = eating.pose(GOALS.index("middle"), stab, 0.0)
    p_star, r_star = fork_frame(robot, GOALS.index("middle"), stab, 0.0)
    start = eating.start
    data = mujoco.MjData(robot.model)

    def cost(q):
        """The participants' cost of the pose at q: the progress of a move onto the waypoint."""
        pos, axis, _, _ = tip_frames(robot, data, q[None])
        return progress_gain(pos, axis, (p_star - pos)[:, None], r_star[None, None, :, 2], p_star[None],
                             r_star[None, :, 2], 0.125)[0, 0]  # fmt: skip

    assert cost(target) < 0.01  # q* is the waypoint's pose
    # the via point: a bit towards the target, mostly up the cost's gradient across that
    grad = np.array([(cost(start + 1e-6 * e) - cost(start)) / 1e-6 for e in np.eye(7)])
    forward = (target - start) / np.linalg.norm(target - start)
    across = grad - (grad @ forward) * forward
    via = start + 0.05 * forward + 0.3 * across / np.linalg.norm(across)
    return DetourDecoder(start, target, via, control.action_scale, control.dt), (p_star, r_star[:, 2])


def test_one_step_progress_of_every_detour_input_is_not_positive(eating, detour):
    decoder, (p_star, d_star) = detour
    robot, dt = eating.robot, eating.robot.control.dt
    pos, axis, jp, jr = tip_frames(robot, mujoco.MjData(robot.model), eating.start[None])
    grid = np.stack(np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 5), indexing="ij"), -1).reshape(
        -1, 2
    )
    phi = decoder.decode_numpy(grid[None], eating.start[None, None], np.full((1, 1, 4), 0.25))
    dp, new_dir = tip_motion(jp, jr, axis, dt * phi)
    gain = progress_gain(pos, axis, dp, new_dir, p_star[None], d_star[None], 0.125)
    assert gain.max() <= 1e-6 and gain.min() < -0.3 * dt * 0.15


def test_a_planner_finds_the_detour_a_one_step_participant_does_not(eating, detour):
    decoder, _ = detour
    kw = dict(decoder=decoder, n=1, horizon=300, interfaces=("LA",))
    planned, one_step = _run(planning, eating, **kw), _run(participants, eating, **kw)
    la = planned.condition == "LA"  # unassisted: nothing but the participant moves the arm
    assert np.all(planned.waypoint[la] >= 1)
    assert np.all(one_step.waypoint[la] == 0)


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"replan": 0.0}, "replan must be in"),
        ({"replan": "1"}, "replan must be a number"),
        ({"holds": ()}, "holds must hold a value"),
        ({"holds": (2.0, 0.5)}, "ascending order"),
        ({"holds": (0.5, 0.5)}, "must not repeat"),
        ({"holds": (0.1, -1.0)}, r"holds\[1\] must be in"),
        ({"coarse": 0}, "coarse must be an integer"),
    ],
)
def test_config_errors_are_one_clear_line(settings, match):
    with pytest.raises(ConfigError, match=match) as err:
        PlanConfig(**settings)
    assert "\n" not in str(err.value)


def test_holds_must_be_whole_steps(eating):
    with pytest.raises(ConfigError, match="whole number of control steps") as err:
        _run(planning, eating, horizon=2, plan=PlanConfig(holds=(0.15,)))
    assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match="multiple of coarse"):
        PlanConfig(holds=(0.5, 0.8)).steps(0.1)

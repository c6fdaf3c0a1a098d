"""The latent-action property (lasa.evidence.latent_measure, .latent_property) on hand-built decoders
whose answer is known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence import latent_measure as lm
from lasa.evidence import latent_property as lp
from lasa.world.robot import load_robot
from lasa.world.task import CupTask, make_cup_task


@pytest.fixture(scope="module")
def task() -> CupTask:
    return make_cup_task(load_robot("planar5"))


@dataclasses.dataclass
class CurveDecoder:
    """The property by construction: confident, z moves along the believed goal's grasp curve;
    unsure, z < 0 heads for the left cup and z > 0 for the right one, at sigma_h."""

    task: CupTask
    speed: float
    robot: str = "planar5"
    n_goals: int = 2
    z_dim: int = 1

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        z = np.broadcast_to(z, s.shape[:-1] + (1,))[..., 0]
        thetas = np.linspace(0.0, 1.0, 201)
        confident = b.max(axis=-1) > 0.9
        # the goal: the believed one when confident, else the one z points at
        goal = np.where(confident, b.argmax(axis=-1), np.where(z < 0, 0, 1))
        out = np.zeros(s.shape)
        on_curve = np.zeros(s.shape[:-1], dtype=bool)
        for g in range(self.n_goals):
            curve = self.task.target(g, thetas)  # (T, n)
            tangent = np.gradient(curve, axis=0)
            tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
            dist = np.linalg.norm(s[..., None, :] - curve, axis=-1)
            mine = confident & (goal == g) & (dist.min(axis=-1) < 0.05)
            out = np.where(mine[..., None], self.speed * z[..., None] * tangent[dist.argmin(axis=-1)], out)
            on_curve |= mine
        return np.where(on_curve[..., None], out, self.head(goal, s))

    def head(self, goal: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Towards each row's goal configuration at sigma_h, slowing within 0.1 sigma_h of it."""
        to_goal = self.task.goals[goal] - s
        dist = np.linalg.norm(to_goal, axis=-1, keepdims=True)
        return self.speed * to_goal / np.maximum(dist, 0.1 * self.speed)


@dataclasses.dataclass
class TwoHalvesDecoder(CurveDecoder):
    """Both halves by construction: confident, |z| <= 0.7 moves along the believed cup's grasp
    curve and a larger deflection heads for the cup it points at (z < 0 left, z > 0 right);
    unsure, as :class:`CurveDecoder`."""

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        zz = np.broadcast_to(z, s.shape[:-1] + (1,))[..., 0]
        curve = super().decode_numpy(np.clip(zz / 0.7, -1, 1)[..., None], s, b)
        leave = (b.max(axis=-1) > 0.9) & (np.abs(zz) > 0.7)
        return np.where(leave[..., None], self.head(np.where(zz < 0, 0, 1), s), curve)


@dataclasses.dataclass
class DriftDecoder:
    """Every input turns the base joint at sigma_h: the tool never stays anywhere."""

    speed: float
    robot: str = "planar5"
    n_goals: int = 2
    z_dim: int = 1

    def decode_numpy(self, z: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.zeros(np.broadcast_shapes(s.shape, z.shape[:-1] + (s.shape[-1],)))
        out[..., 0] = self.speed * np.sign(z[..., 0] + 1e-12)
        return out


def _measure(task: CupTask, decoder: object, name: str) -> pd.DataFrame:
    control = task.robot.control
    config = lm.PropertyConfig(n_inputs=16)
    return lm.measure(task, decoder, control, config, source="test", task_name="cups", decoder_name=name)  # type: ignore[arg-type]


def test_a_decoder_built_to_stay_has_the_stay_half_only(task: CupTask) -> None:
    frame = _measure(task, CurveDecoder(task, task.robot.control.action_scale), "curve")
    table = lp.summary(frame)
    assert list(table.goal) == list(task.goal_names)
    # every input moves along the grasp curve: the tip stays on the preference set
    assert (table.stay_share == 1.0).all()
    # held 4 s at sigma_h, the inputs reach both ends of the curve from its middle
    assert (table.theta_min < 0.1).all() and (table.theta_max > 0.9).all()
    assert table.stay_holds.all() and table.all_reached.all()
    home = frame[frame.context == "uncertain"]
    # z < 0 leads to the left cup, z > 0 to the right one
    assert set(home[home.z1 < 0].reached) == {task.goal_names[0]}
    assert set(home[home.z1 > 0].reached) == {task.goal_names[1]}
    # confident, no input ever leaves the grasp curve: the leave half fails, and with it the rule
    assert (table.leave_min == 0).all() and (table.leave_la_min == 0).all()
    assert not table.leave_holds.any() and not table.has_property.any() and not lp.holds(table).any()


def test_a_decoder_built_with_both_halves_meets_the_rule(task: CupTask) -> None:
    frame = _measure(task, TwoHalvesDecoder(task, task.robot.control.action_scale), "two")
    table = lp.summary(frame)
    leave = frame[frame.context == "leave"]
    assert set(leave.start) == {"grasp"} and set(leave.condition) == set(lp.CONDITIONS)
    # 16 inputs on [-1, 1]: the 3 beyond 0.7 on the other cup's side head for it, and under LA+SA
    # (the condition the rule reads) they reach it
    table_ = lp.leave_table(frame)
    assert (table_[table_.condition == "LA+SA"].inputs == 3).all()
    arrived = leave[leave.reached == leave.target]
    far = np.where(arrived.goal == task.goal_names[0], arrived.z1 > 0.7, arrived.z1 < -0.7)
    assert far.all() and (arrived.exit_time > 0).all() and (arrived.exit_time <= 10.0).all()
    assert (table_[table_.condition == "LA+SA"].exit_time > 0).all()
    assert (table.stay_share >= 0.5).all() and table.stay_holds.all()
    # the rule asks 7 of 64, i.e. 1.75 of 16: 3 inputs suffice
    assert table.leave_holds.all() and table.has_property.all() and bool(lp.holds(table).all())
    both = pd.concat([frame, _measure(task, CurveDecoder(task, task.robot.control.action_scale), "curve")])
    assert lp.choose(lp.summary(both)) == "two"  # the stay-only decoder ranks below


def test_a_drifting_decoder_lacks_it_and_the_rule_prefers_the_other(task: CupTask) -> None:
    speed = task.robot.control.action_scale
    drift = _measure(task, DriftDecoder(speed), "drift")
    table = lp.summary(drift)
    assert (table.stay_share == 0.0).all() and not table.has_property.any()
    assert (table.theta_range == 0.0).all()  # nothing stays, so no preference is reached
    conf = drift[drift.context == "confident"]
    assert (conf.drift > 0.02).all()  # the base joint swings the tip at well over 2 cm/s
    both = pd.concat([drift, _measure(task, CurveDecoder(task, speed), "curve")], ignore_index=True)
    assert lp.choose(lp.summary(both)) == "curve"  # neither meets the rule; curve has the stay half


def test_summary_counts_by_hand() -> None:
    base = {
        "source": "s",
        "robot": "r",
        "task": "t",
        "decoder": "d",
        "z2": np.nan,
        "drift": 0.0,
        "distance": 0.0,
    }
    at = {  # per goal: (z1, stays, theta) of four inputs held there with a confident belief
        "a": ((-1.0, True, 0.1), (-0.5, True, 0.8), (0.5, False, 0.5), (1.0, True, 0.3)),
        "b": ((-1.0, True, 0.2), (-0.5, False, 0.1), (0.5, False, 0.5), (1.0, False, 0.9)),
    }
    conf = {"context": "confident", "stroke": 0.0, "reached": "a"}
    rows = [
        {**base, **conf, "goal": g, "z1": z, "stays": st, "theta": th}
        for g, inputs in at.items()
        for z, st, th in inputs
    ]
    rows += [
        {
            **base,
            "context": "uncertain",
            "goal": "home",
            "z1": z,
            "stays": False,
            "theta": np.nan,
            "stroke": np.nan,
            "reached": r,
        }
        for z, r in ((-1.0, "a"), (-0.5, "a"), (0.5, "-"), (1.0, "a"))
    ]
    # leaving: from a's two phase ends, under LA+SA, 3 and 1 of the 4 inputs reach b (LA: 0 and 4);
    # from b's one end, every input reaches a
    leave = {("a", "p", "LA+SA"): 3, ("a", "q", "LA+SA"): 1, ("a", "p", "LA"): 0, ("a", "q", "LA"): 4}
    leave |= {("b", "p", "LA+SA"): 4, ("b", "p", "LA"): 4}
    rows += [
        {
            **base,
            "context": "leave",
            "goal": g,
            "z1": z,
            "stays": False,
            "theta": np.nan,
            "stroke": np.nan,
            "reached": ("b" if g == "a" else "a") if i < n else "-",
            "start": st,
            "condition": cond,
            "target": "b" if g == "a" else "a",
            "exit_time": 1.0 + i if i < n else np.nan,
        }
        for (g, st, cond), n in leave.items()
        for i, z in enumerate((-1.0, -0.5, 0.5, 1.0))
    ]
    frame = pd.DataFrame(rows)
    table = lp.summary(frame).set_index("goal")
    assert table.loc["a", "leave_min"] == 1 and table.loc["a", "leave_la_min"] == 0
    assert table.loc["b", "leave_min"] == 4 and table.loc["b", "leave_la_min"] == 4
    # 7 of 64 is 0.4375 of 4 inputs: a single input suffices here
    assert table.leave_holds.all()
    counts = lp.leave_table(frame).set_index(["goal", "start", "condition"])
    assert counts.loc[("a", "p", "LA+SA"), "exit_time"] == 2.0  # median of 1, 2, 3 s
    assert np.isnan(counts.loc[("a", "p", "LA"), "exit_time"])
    assert table.loc["a", "stay_share"] == 0.75 and table.loc["b", "stay_share"] == 0.25
    assert table.loc["a", "theta_range"] == pytest.approx(0.7) and table.loc["b", "theta_range"] == 0.0
    assert table.loc["a", "from_home"] == 0.75 and table.loc["b", "from_home"] == 0.0
    assert not table.all_reached.any()  # nothing reaches b from home
    # nothing reaches b from home: the property holds nowhere, though a has the stay half
    assert bool(table.loc["a", "stay_holds"]) and not bool(table.loc["b", "stay_holds"])
    assert not table.has_property.any()


def test_choose_orders_by_rule_then_reach_then_goals_then_shares() -> None:
    def rows(
        decoder: str, reached: bool, shares: list[float], tilts: list[float], leave: float = 64
    ) -> list[dict[str, object]]:
        return [
            {
                "task": "t",
                "decoder": decoder,
                "all_reached": reached,
                "stay_share": s,
                "theta_range": r,
                "leave_min": leave,
                "stay_holds": s >= lp.STAY_SHARE and r >= lp.TILT_RANGE,
                "has_property": reached
                and s >= lp.STAY_SHARE
                and r >= lp.TILT_RANGE
                and leave >= lp.LEAVE_COUNT,
            }
            for s, r in zip(shares, tilts, strict=True)
        ]

    table = pd.DataFrame(
        rows("unreached", False, [1.0, 1.0], [1.0, 1.0])
        + rows("one_goal", True, [0.9, 0.2], [1.0, 1.0])
        + rows("low_share", True, [0.6, 0.55], [1.0, 1.0])
        + rows("high_share", True, [0.6, 0.7], [0.6, 0.6])
    )
    assert lp.choose(table) == "high_share"  # both goals, its smallest share 0.6 > 0.55
    assert lp.choose(table[table.decoder != "high_share"]) == "low_share"
    assert lp.choose(table[table.decoder.isin(["unreached", "one_goal"])]) == "one_goal"
    with pytest.raises(ConfigError, match="one task"):
        lp.choose(pd.concat([table, table.assign(task="u")]))
    # a decoder that stays everywhere but leaves nowhere ranks below one with both halves
    stay_only = pd.DataFrame(rows("stay_only", True, [1.0, 1.0], [1.0, 1.0], leave=0))
    both = pd.DataFrame(rows("both", True, [0.5, 0.5], [0.5, 0.5], leave=7))
    pair = pd.concat([stay_only, both], ignore_index=True)
    assert lp.choose(pair) == "both" and list(lp.holds(pair)) == [False, True]
    # neither meets the rule: the one with more goals holding the stay half ranks first
    weak = pd.DataFrame(rows("weak", True, [0.4, 0.4], [1.0, 1.0], leave=30))
    assert lp.choose(pd.concat([weak, stay_only], ignore_index=True)) == "stay_only"


def test_ring_and_bad_input() -> None:
    two = lm.ring(8, 2)
    assert two.shape == (8, 2) and np.allclose(np.linalg.norm(two, axis=1), 1.0)
    one = lm.ring(7, 1)
    assert one.shape == (8, 1) and not np.any(one == 0.0) and one.min() == -1.0 and one.max() == 1.0
    with pytest.raises(ConfigError, match="z_dim=3"):
        lm.ring(8, 3)
    with pytest.raises(ConfigError, match="hold"):
        lm.PropertyConfig(hold=0.0)
    with pytest.raises(ConfigError, match="n_inputs"):
        lm.PropertyConfig(n_inputs=1)
    with pytest.raises(ConfigError, match="leave_hold"):
        lm.PropertyConfig(leave_hold=-1.0)


def test_phase_ends_are_the_eating_tasks_stroke_ends() -> None:
    from lasa.world.eating import GOALS, fork_frame, make_eating_task

    eating = make_eating_task()
    ends = {GOALS[g]: lm.phase_ends(eating, g) for g in range(eating.n_goals)}
    assert {g: [label for label, _ in e] for g, e in ends.items()} == {
        "rice": ["dip"],
        "middle": ["cut", "stab"],
        "icing": ["scoop"],
        "plate": ["place"],
    }
    thetas = {"dip": 0.0, "cut": 0.5, "stab": 0.0, "scoop": 1.0, "place": 0.0}
    for g, name in enumerate(GOALS):
        for label, state in ends[name]:
            tip = eating.robot.grasp_pose(state)[0]
            assert np.linalg.norm(tip - fork_frame(eating.robot, g, thetas[label], 1.0)[0]) < 2e-3


def test_phase_ends_of_the_cups_are_their_mid_grasps(task: CupTask) -> None:
    for g in range(task.n_goals):
        ((label, state),) = lm.phase_ends(task, g)
        assert label == "grasp" and np.allclose(state, task.target(g, 0.5))

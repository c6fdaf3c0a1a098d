"""The latent-action property (lasa.evidence.latent_property) on hand-built decoders whose answer is known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
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
        to_goal = self.task.goals[goal] - s
        dist = np.linalg.norm(to_goal, axis=-1, keepdims=True)
        head = self.speed * to_goal / np.maximum(dist, 0.1 * self.speed)
        return np.where(on_curve[..., None], out, head)


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
    config = lp.PropertyConfig(n_inputs=16)
    return lp.measure(task, decoder, control, config, source="test", task_name="cups", decoder_name=name)  # type: ignore[arg-type]


def test_a_decoder_built_to_have_the_property_has_it(task: CupTask) -> None:
    frame = _measure(task, CurveDecoder(task, task.robot.control.action_scale), "curve")
    table = lp.summary(frame)
    assert list(table.goal) == list(task.goal_names)
    # every input moves along the grasp curve: the tip stays on the preference set
    assert (table.stay_share == 1.0).all()
    # held 4 s at sigma_h, the inputs reach both ends of the curve from its middle
    assert (table.theta_min < 0.1).all() and (table.theta_max > 0.9).all()
    assert table.has_property.all() and table.all_reached.all()
    home = frame[frame.context == "uncertain"]
    # z < 0 leads to the left cup, z > 0 to the right one
    assert set(home[home.z1 < 0].reached) == {task.goal_names[0]}
    assert set(home[home.z1 > 0].reached) == {task.goal_names[1]}


def test_a_drifting_decoder_lacks_it_and_the_rule_prefers_the_other(task: CupTask) -> None:
    speed = task.robot.control.action_scale
    drift = _measure(task, DriftDecoder(speed), "drift")
    table = lp.summary(drift)
    assert (table.stay_share == 0.0).all() and not table.has_property.any()
    assert (table.theta_range == 0.0).all()  # nothing stays, so no preference is reached
    conf = drift[drift.context == "confident"]
    assert (conf.drift > 0.02).all()  # the base joint swings the tip at well over 2 cm/s
    both = pd.concat([drift, _measure(task, CurveDecoder(task, speed), "curve")], ignore_index=True)
    assert lp.choose(lp.summary(both)) == "curve"


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
    table = lp.summary(pd.DataFrame(rows)).set_index("goal")
    assert table.loc["a", "stay_share"] == 0.75 and table.loc["b", "stay_share"] == 0.25
    assert table.loc["a", "theta_range"] == pytest.approx(0.7) and table.loc["b", "theta_range"] == 0.0
    assert table.loc["a", "from_home"] == 0.75 and table.loc["b", "from_home"] == 0.0
    assert not table.all_reached.any()  # nothing reaches b from home
    assert bool(table.loc["a", "has_property"]) and not bool(table.loc["b", "has_property"])


def test_choose_orders_by_reach_then_goals_then_shares() -> None:
    def rows(decoder: str, reached: bool, shares: list[float], tilts: list[float]) -> list[dict[str, object]]:
        return [
            {
                "task": "t",
                "decoder": decoder,
                "all_reached": reached,
                "stay_share": s,
                "theta_range": r,
                "has_property": s >= lp.STAY_SHARE and r >= lp.TILT_RANGE,
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


def test_ring_and_bad_input() -> None:
    two = lp.ring(8, 2)
    assert two.shape == (8, 2) and np.allclose(np.linalg.norm(two, axis=1), 1.0)
    one = lp.ring(7, 1)
    assert one.shape == (8, 1) and not np.any(one == 0.0) and one.min() == -1.0 and one.max() == 1.0
    with pytest.raises(ConfigError, match="z_dim=3"):
        lp.ring(8, 3)
    with pytest.raises(ConfigError, match="hold"):
        lp.PropertyConfig(hold=0.0)
    with pytest.raises(ConfigError, match="n_inputs"):
        lp.PropertyConfig(n_inputs=1)

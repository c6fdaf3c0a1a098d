"""The dataset D of demonstrations: (s, a, b) tuples, each labelled by its demonstration
(collected by :mod:`lasa.people.demos`, saved as ``.npz``)."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np

from lasa.base.errors import ArtifactError
from lasa.base.io import load_npz, save_npz
from lasa.world.robot import Robot
from lasa.world.task import CupTask

REACH, ADJUST, HOLD, STROKE = 0, 1, 2, 3  # phase labels of a tuple (strokes: the eating task)
PHASE_NAMES = ("reach", "adjust", "hold", "stroke")


@dataclasses.dataclass(frozen=True)
class Demonstrations:
    """The dataset D, one row per (s, a, b) tuple."""

    robot: str
    states: np.ndarray  # s, (N, n) [rad]
    actions: np.ndarray  # a, (N, n) [rad/s]
    beliefs: np.ndarray  # b, (N, G)
    demo: np.ndarray  # the demonstration each tuple belongs to, (N,)
    goal: np.ndarray  # the demonstrated cup, (N,)
    theta: np.ndarray  # the preference moved towards, (N,)
    phase: np.ndarray  # REACH, ADJUST, HOLD or STROKE, (N,)
    perturbed: np.ndarray  # whether the tuple is a noisy copy, (N,)

    def __len__(self) -> int:
        return len(self.states)

    def clean(self) -> Demonstrations:
        """The tuples that are not noisy copies (the demonstrations themselves)."""
        keep = ~self.perturbed
        rows = {f.name: getattr(self, f.name)[keep] for f in dataclasses.fields(self) if f.name != "robot"}
        return dataclasses.replace(self, **rows)

    def showcase(self, task: CupTask) -> list[tuple[int, str]]:
        """(index, caption) of clean demonstrations from the start pose: a top and a side grasp at
        each cup, cup by cup, top grasp first."""
        clean = self.clean()
        first = np.r_[0, np.flatnonzero(np.diff(clean.demo)) + 1]
        starts = dict(zip(clean.demo[first].tolist(), clean.states[first], strict=True))
        home = [d for d, s in starts.items() if np.allclose(s, task.start)]
        theta = {d: float(clean.theta[(clean.demo == d) & (clean.phase == REACH)][0]) for d in home}
        goal = {d: int(clean.goal[clean.demo == d][0]) for d in home}
        out = []
        for g in range(task.n_goals):
            for wanted in (0.0, 1.0):
                d = min((d for d in home if goal[d] == g), key=lambda d: abs(theta[d] - wanted))
                caption = f"demo {d}: {task.goal_names[g]} cup, reach to theta={theta[d]:.2f}, then adjust"
                out.append((d, caption))
        return out


def add_noisy_copies(
    clean: Demonstrations,
    robot: Robot,
    action_scale: float,
    copies: tuple[int, float, float],
    rng: np.random.Generator,
) -> Demonstrations:
    """``clean`` and ``n`` noisy copies of every tuple, ``copies = (n, std, gain)``: the state perturbed by
    N(0, std^2) [rad] (clipped to the joint limits), the action corrected back towards the demonstrated
    state, :math:`a + k (s - \tilde s)` with gain k [1/s], clipped below 0.99 sigma_h (``action_scale``);
    labels and beliefs repeated, the copies after the tuples (``perturbed`` True)."""
    n_perturb, std, gain = copies
    limit = 0.99 * action_scale
    states, actions = clean.states, clean.actions
    pairs = [(states, actions)]
    for _ in range(n_perturb):
        s_new = robot.clip(states + rng.normal(0.0, std, states.shape))
        a_new = actions + gain * (states - s_new)
        norm = np.linalg.norm(a_new, axis=1, keepdims=True)
        pairs.append((s_new, np.where(norm > limit, a_new * limit / np.maximum(norm, 1e-12), a_new)))
    reps = n_perturb + 1
    s, a = map(np.concatenate, zip(*pairs, strict=True))
    beliefs = np.tile(clean.beliefs, (reps, 1))
    demo, goal, theta, phase = (np.tile(x, reps) for x in (clean.demo, clean.goal, clean.theta, clean.phase))
    perturbed = np.arange(len(s)) >= len(states)
    return Demonstrations(robot.name, s, a, beliefs, demo, goal, theta, phase, perturbed)


def save_demonstrations(demos: Demonstrations, path: str | os.PathLike[str]) -> Path:
    """Atomically save a dataset to ``.npz``."""
    return save_npz(path, **{f.name: np.asarray(getattr(demos, f.name)) for f in dataclasses.fields(demos)})


def load_demonstrations(
    path: str | os.PathLike[str],
    robot: str | None = None,
    make_hint: str = "make figures (notebook 01_demonstrations)",
) -> Demonstrations:
    """Load a dataset saved by :func:`save_demonstrations`, checking its robot."""
    arrays = load_npz(path, make_hint)
    try:
        fields = {f.name: arrays[f.name] for f in dataclasses.fields(Demonstrations)}
        demos = Demonstrations(**{**fields, "robot": str(fields["robot"])})  # type: ignore[arg-type]
    except KeyError as exc:
        raise ArtifactError(f"{path} lacks field {exc}; re-make it with: {make_hint}") from exc
    if robot is not None and demos.robot != robot:
        raise ArtifactError(
            f"{path} holds demonstrations for {demos.robot!r}, not {robot!r}; re-make it with: {make_hint}"
        )
    return demos

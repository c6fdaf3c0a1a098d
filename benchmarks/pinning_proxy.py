"""The pipeline's kinds of work, timed in one process: what pinning the kernels to AVX2 costs.

Run by ``benchmarks/bench.py`` (part ``pinning``) twice per round, once with the kernels pinned
(lasa's defaults, :mod:`lasa.runtime`) and once with each library free to pick its own
(``ATEN_CPU_CAPABILITY=default`` and so on). Prints one JSON line: the thread CPU time [s] of

- ``training``: entropy-regularised decoder fine-tuning steps (Eq. T6; notebooks 03 and 10);
- ``forward``: the batched decoder forward of the simulations (``decode_numpy``, 1024 x 21 rows);
- ``belief``: belief log-likelihoods of 4096 states against polyline goal sets (float64).
"""

from __future__ import annotations

import json
import sys
import time

from lasa.runtime import pin

pin()  # first: the kernels pinned (unless the caller set them) before numpy loads

import numpy as np  # noqa: E402
import torch  # noqa: E402

from lasa.method.belief import belief_targets, log_likelihood  # noqa: E402
from lasa.method.train import TrainConfig, train_decoder  # noqa: E402
from lasa.people.demos import DemoConfig, collect_demonstrations  # noqa: E402
from lasa.world.robot import load_robot  # noqa: E402
from lasa.world.task import make_cup_task  # noqa: E402


def _timed(call) -> float:
    start = time.thread_time()
    call()
    return time.thread_time() - start


def main(steps: int) -> None:
    torch.set_num_threads(1)
    robot = load_robot("planar5")
    task = make_cup_task(robot)
    control = robot.control
    demos = collect_demonstrations(task, control, DemoConfig(n_theta=3, n_starts=1, n_adjust=1, seed=0))
    goal_sets = belief_targets(task, control.likelihood)
    base, _ = train_decoder(demos, control, TrainConfig(steps=20, seed=0), progress=False)
    fine = TrainConfig(steps=steps, entropy_lambda=0.3, seed=0)
    rng = np.random.default_rng(0)
    z = rng.uniform(-1, 1, (1, 21, base.z_dim))
    s = task.start + rng.normal(0, 0.2, (1024, 1, robot.n_joints))
    b = rng.dirichlet(np.ones(task.n_goals), (1024, 1))
    states = task.start + rng.normal(0, 0.3, (4096, robot.n_joints))
    actions = rng.normal(0, 0.02, states.shape)
    out = {
        "training": _timed(
            lambda: train_decoder(demos, control, fine, goal_sets=goal_sets, init=base, progress=False)
        ),
        "forward": _timed(lambda: [base.decode_numpy(z, s, b) for _ in range(20)]),
        "belief": _timed(
            lambda: [
                log_likelihood(states, actions, goal_sets, control.dt, control.belief_beta) for _ in range(20)
            ]
        ),
        "capability": torch.backends.cpu.get_cpu_capability(),
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 150)

"""Shared fixtures: the planar5 task, a small dataset and a briefly trained decoder.

The runtime is pinned first (:func:`lasa.runtime.pin`, as make's exports do): MUJOCO_GL stays
``osmesa`` for the whole test process (the render test and the notebooks the notebook tests start
need it; MuJoCo touches OpenGL only when a Renderer is created) and the kernels are pinned before
numpy and torch load.
"""

from __future__ import annotations

from lasa.runtime import pin

pin()

import pytest  # noqa: E402
import torch  # noqa: E402

from lasa.method.train import TrainConfig, train_decoder  # noqa: E402
from lasa.people.demos import DemoConfig, collect_demonstrations  # noqa: E402
from lasa.world.robot import Robot, load_robot  # noqa: E402
from lasa.world.task import CupTask, make_cup_task  # noqa: E402

torch.set_num_threads(1)

SMALL_DEMOS = DemoConfig(n_theta=3, n_starts=1, n_adjust=1, n_perturb=1, seed=0)
SMALL_TRAIN = TrainConfig(steps=150, hidden=32, depth=2, batch_size=128, log_every=50, seed=0)


@pytest.fixture(scope="session")
def robot() -> Robot:
    return load_robot("planar5")


@pytest.fixture(scope="session")
def task(robot: Robot) -> CupTask:
    return make_cup_task(robot)


@pytest.fixture(scope="session")
def demos(task: CupTask):
    return collect_demonstrations(task, task.robot.control, SMALL_DEMOS)


@pytest.fixture(scope="session")
def model(demos, task: CupTask):
    trained, _ = train_decoder(demos, task.robot.control, SMALL_TRAIN, progress=False)
    return trained


@pytest.fixture(scope="session")
def panda_task() -> CupTask:
    return make_cup_task(load_robot("panda"))


@pytest.fixture(scope="session")
def panda_model(panda_task: CupTask):
    data = collect_demonstrations(panda_task, panda_task.robot.control, SMALL_DEMOS)
    trained, _ = train_decoder(data, panda_task.robot.control, SMALL_TRAIN, progress=False)
    return trained


# The test files that take longest (summed --durations of a `make test` run, longest first): under
# pytest-xdist's --dist loadfile (`make test`), the workers take the files in this order and the rest
# after them, so that no long file starts last while the other worker sits idle. Only the order of
# whole files changes; each file's tests keep theirs.
SLOWEST_FILES = (
    "test_notebooks.py", "test_bench.py", "test_web.py", "test_teleop.py", "test_docs.py", "test_franka.py",
    "test_study_claims.py", "test_study_power.py", "test_figure_titles.py", "test_robustness.py",
    "test_notebook_caps.py", "test_video.py", "test_demos.py", "test_init.py", "test_entropy.py",
    "test_web_study.py", "test_runtime.py", "test_franka_kinematics.py", "test_preregister.py",
    "test_planning.py", "test_kinesthetic.py", "test_timings.py", "test_makedeps.py", "test_verdicts.py",
    "test_rollback.py", "test_verify.py", "test_sim1_to_sim3.py",
)  # fmt: skip


def pytest_collection_modifyitems(config, items):
    """In an xdist worker (whose collection order the controller schedules by), the slowest files first."""
    if hasattr(config, "workerinput"):
        rank = {name: i for i, name in enumerate(SLOWEST_FILES)}
        items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep their order


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """--dist loadfile in the collection's order (above), not xdist's default of the most tests first."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    config.option.loadscopereorder = False
    return LoadFileScheduling(config, log)


# Files a test leaves for a person to look at (a screenshot, say), listed at the end of the run.
# They ride on the test's report (``user_properties``), which pytest-xdist's workers send back to
# the process that prints the summary.
ARTIFACT = "artifact"


@pytest.fixture
def report_artifact(request):
    """Call as ``report_artifact(description, path)``: the path is printed in the run's summary."""
    return lambda description, path: request.node.user_properties.append((ARTIFACT, (description, str(path))))


def pytest_terminal_summary(terminalreporter):
    reports = [r for outcome in ("passed", "failed") for r in terminalreporter.stats.get(outcome, [])]
    found = [
        value for r in reports if r.when == "call" for key, value in r.user_properties if key == ARTIFACT
    ]
    if found:
        terminalreporter.section("files left for inspection")
        for description, path in found:
            terminalreporter.write_line(f"{description}: {path}")

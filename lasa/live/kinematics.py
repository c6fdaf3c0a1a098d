"""The connected arm's forward kinematics against the package's Panda, before a session trusts either.

The decoders' Panda (:mod:`lasa.world.franka`: Franka's DH table, flange and Franka Hand TCP) and the FR3
share their kinematics and differ in joint limits, so at any joint vector both arms reach, libfranka's end
effector pose must be the package Panda's :data:`lasa.world.franka.EE_SITE`. :func:`check_kinematics` moves
the arm (a real one at its FCI address, or ``franky-sim``) to random configurations inside the shared limits
and compares two pairs from one state sample:

- **desired**: the motion generator's joints ``q_d`` and pose ``O_T_EE_d`` (libfranka computes the one from
  the other), free of the joint controller's tracking error: the kinematics alone;
- **measured**: the measured joints ``q`` and pose ``O_T_EE``. On a real arm libfranka computes ``O_T_EE``
  from ``q``; ``franky-sim`` 1.0.4 reports the pose at ``q_d`` instead (its ``kinematics`` returns pinocchio's
  frame placement by reference, which the ``O_T_EE_d`` evaluation overwrites), so there this pair differs by
  the tracking error ``|q_d - q|``, reported beside."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from lasa.live.link import LinkError
from lasa.world.franka import fk_errors, shared_configurations
from lasa.world.robot import Robot, load_robot

CHECK_SPEED = 0.5  # franky's relative dynamics factor of the moves between configurations
STATE_FIELDS = ("q", "q_d", "O_T_EE", "O_T_EE_d")  # what :func:`measure` reads of each state sample


def measure(arm: Any, targets: np.ndarray, speed: float = CHECK_SPEED) -> dict[str, np.ndarray]:
    """Move ``arm`` (a ``franky.Robot``) to each joint vector of ``targets`` (n, 7) [rad] at ``speed`` and
    read one state sample there: the joints ``q``, ``q_d`` (n, 7) and poses ``O_T_EE``, ``O_T_EE_d``
    (n, 4, 4). LinkError if a move fails (the arm stops where it is)."""
    import franky

    fields: dict[str, list[np.ndarray]] = {k: [] for k in STATE_FIELDS}
    for target in np.atleast_2d(targets):
        goal = franky.JointState(np.asarray(target, float).tolist())
        try:
            arm.move(franky.JointMotion(goal, relative_dynamics_factor=speed))
        except franky.Exception as exc:
            raise LinkError(f"the move to {np.round(target, 3).tolist()} failed: {exc}") from exc
        state = arm.state  # one sample: current_joint_state and current_cartesian_state would be two
        for key in STATE_FIELDS:
            value = getattr(state, key)
            fields[key].append(np.array(value.matrix if key.startswith("O_") else value, float))
    return {k: np.array(v) for k, v in fields.items()}


def compare(robot: Robot, fields: dict[str, np.ndarray]) -> pd.DataFrame:
    """The table of :func:`check_kinematics` from :func:`measure`'s ``fields``."""
    desired = fk_errors(robot, fields["q_d"], fields["O_T_EE_d"])
    measured = fk_errors(robot, fields["q"], fields["O_T_EE"])
    for column in ("position_error_m", "orientation_error_rad"):
        desired[f"measured_{column}"] = measured[column]
    desired["tracking_error_rad"] = np.abs(fields["q_d"] - fields["q"]).sum(axis=1)
    return desired


def check_kinematics(
    arm: Any,
    n: int = 5,
    seed: int = 0,
    margin: float = 0.2,
    speed: float = CHECK_SPEED,
    robot: Robot | None = None,
) -> tuple[pd.DataFrame, dict[str, float]]:
    """Compare the connected ``arm``'s end effector with the package Panda's (``robot``, default
    ``load_robot("panda")``) at ``n`` random configurations (``seed``) inside the shared limits, ``margin``
    [rad] from them and off the table (:func:`lasa.world.franka.shared_configurations`). A real arm moves
    there: clear its workspace first.

    Returns:
        One row per configuration: ``q0``..``q6`` (the desired joints), the desired pair's
        ``position_error_m`` and ``orientation_error_rad`` (:func:`lasa.world.franka.fk_errors`), the measured
        pair's ``measured_position_error_m`` and ``measured_orientation_error_rad``, and
        ``tracking_error_rad`` (sum over joints of ``|q_d - q|``); and the largest of each error column.
    """
    robot = robot or load_robot("panda")
    table = compare(robot, measure(arm, shared_configurations(n, seed, margin), speed))
    worst = table.drop(columns=[f"q{i}" for i in range(7)]).max()
    return table, {k: float(v) for k, v in worst.items()}

"""The world: the robots (MuJoCo models, kinematics), IK (mink) and the goal tasks.

The tasks are goal tasks (:mod:`lasa.world.goals`): the cups of sims 1-4 and the eating
scene of the study.
"""

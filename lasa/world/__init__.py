"""The world: the robots, their kinematics and IK, and the goal tasks (the cups, the eating scene)."""

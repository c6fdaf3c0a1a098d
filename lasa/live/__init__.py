"""Live use: the station, teleoperation in MuJoCo's viewer, input devices, session logs and the
study kit.

No notebook imports this package, so an edit here leaves ``make figures`` with nothing to do.
"""

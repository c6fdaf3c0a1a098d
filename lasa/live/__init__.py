"""Live use: the station, the session loop, teleoperation in MuJoCo's viewer, the web study, devices and the
study kit. No notebook imports this package, so an edit here leaves ``make figures`` with nothing to do."""

"""Live use: the station, the session loop, teleoperation in MuJoCo's viewer, the web study, devices and the
study kit (:mod:`~lasa.live.station`, :mod:`~lasa.live.session`, :mod:`~lasa.live.teleop`,
:mod:`~lasa.live.web`, :mod:`~lasa.live.devices`, :mod:`~lasa.live.studykit`).

No notebook imports this package, so an edit here leaves ``make figures`` with nothing to do.
"""

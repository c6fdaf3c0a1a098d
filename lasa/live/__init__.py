"""Live use: the station, teleoperation in MuJoCo's viewer, the web study's server, input devices
and the study kit.

- :mod:`~lasa.live.station`: the robot side of a session, one control step per sample;
- :mod:`~lasa.live.teleop`: drive a condition in MuJoCo's viewer, log the session, replay it;
- :mod:`~lasa.live.web`: the eating study in participants' browsers, the control step on the server;
- :mod:`~lasa.live.devices`: a gamepad, the keyboard or a script, made safe for the control loop;
- :mod:`~lasa.live.interrupts`: a session stopped by a signal reads ``interrupted``;
- :mod:`~lasa.live.studykit`: the schedule of conditions and the questionnaire.

The session logs are :mod:`lasa.evidence.sessionlog`, and sample them back for analysis
:mod:`lasa.evidence.sessions`. No notebook imports this package, so an edit here leaves
``make figures`` with nothing to do.
"""

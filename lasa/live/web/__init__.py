"""The eating study in a web browser: one server runs the control step, the page only draws and reads input.

``python -m lasa.live.web --port 8000 --sessions build/sessions`` (``make study-server ARGS=...``) serves
the study; ``python -m lasa.live.web schedule --participants 10 --sessions build/sessions`` writes the
counterbalanced schedule and one link per participant (:mod:`lasa.live.web.tokens`).

- :mod:`~lasa.live.web.tokens`: the links' secret tokens, stored as hashes, and the strict participant ids.
- :mod:`~lasa.live.web.plan`: a participant's protocol (consent, then per condition practice, the two
  tasks and the questionnaire, then thanks) and their progress through it, kept on the server.
- :mod:`~lasa.live.web.protocol`: the messages between page and server, with their size and rate limits.
- :mod:`~lasa.live.web.loop`: the server's 10 Hz loop, one :meth:`lasa.live.station.Station.step` per tick,
  logged by :class:`lasa.evidence.sessionlog.SessionWriter` exactly as ``teleop run`` logs it.
- :mod:`~lasa.live.web.frames`: the robot drawn on the server (MuJoCo's off-screen renderer), sent as JPEG
  (``--frames server``).
- :mod:`~lasa.live.web.scene`: the robot drawn in the browser (``--frames browser``): MuJoCo's WebAssembly
  build and three.js, served by the server, and the trial's scene with its meshes under safe names.
- :mod:`~lasa.live.web.app`: the Starlette application: the page, its files and the WebSocket.
"""

"""The eating study in a web browser: one server runs the control step, the page only draws and reads input
(``python -m lasa.live.web``: :mod:`lasa.live.web.__main__`)."""

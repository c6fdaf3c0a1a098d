"""The eating study in a web browser: one server runs the control step, the page only draws and reads input.

``python -m lasa.live.web --port 8000 --sessions build/sessions`` (``make study-server ARGS=...``) serves
the study; ``python -m lasa.live.web schedule --participants 10 --sessions build/sessions`` writes the
counterbalanced schedule and one link per participant (:mod:`lasa.live.web.tokens`).
"""

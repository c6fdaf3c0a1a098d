"""lasa: Shared Autonomy with Learned Latent Actions (Jeon, Losey & Sadigh, RSS 2020).

A reproducibility package: MuJoCo robots and the cup task, demonstrations, the
conditional-autoencoder decoder phi(z, s, b), shared autonomy (Algorithm 1),
Boltzmann-rational simulated users, and the sweeps behind the paper's figures.

Rendering is software-only by default: ``MUJOCO_GL`` is set to ``osmesa`` here,
before anything imports mujoco (it is read once, at import). Set it yourself first
to override (``egl``, ``glfw``, or ``disable`` when nothing renders).
"""

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")

__version__ = "0.1.0"

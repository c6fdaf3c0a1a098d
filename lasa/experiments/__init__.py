"""One module per experiment: its config, its tidy columns, ``run``, ``claims`` and ``plot``.

Each figure's module (``sim1``-``sim3``, ``latent_map``, ``entropy_ablation``, ``robustness``,
``convergence``, ``eating_task``; the packages ``sim4`` and ``study``) is read by its notebook;
:mod:`.sweep` holds what sims 1-4 share. What a figure module defines: ``docs/method-notes.md``.
"""

"""One module (or package: ``sim4``, ``study``) per figure, read by its notebook: its config, its tidy
columns, ``run``, ``claims``, ``plot`` (``docs/method-notes.md``); :mod:`.sweep`: what sims 1-4 share."""

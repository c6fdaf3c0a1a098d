"""One module per experiment: its config, its tidy columns, ``run``, ``claims`` and ``plot``.

========================  ================================  ===========================
module                    figure                            notebook
========================  ================================  ===========================
:mod:`.latent_map`        what z means, per context         02_decoder_training
:mod:`.entropy_ablation`  the entropy term and its lambda    03_entropy_ablation
:mod:`.sim1`              Fig. sim1, fixed expertise        04_fixed_expertise
:mod:`.sim2`              Fig. sim2, change of mind         05_changing_goals
:mod:`.sim3`              Fig. sim3, learning users         06_learning_users
:mod:`.sim4`              Fig. sim4, new goals              07_new_goals
:mod:`.robustness`        the verdict map                   08_claims_robustness
:mod:`.convergence`       Sec. IV-A, the T1-T4 ball         09_convergence
:mod:`.eating_task`       the eating task's 2-D latent      10_eating_task
:mod:`.study`             the eating study (a package)      11_eating_study
========================  ================================  ===========================

Each figure module defines ``NAME``, ``COLUMNS``, a frozen ``Config`` (from its notebook's
``settings``) and ``plot``; those with claims define ``claims`` (rules: :mod:`lasa.evidence.rules`);
those that simulate define ``run``. :mod:`.sweep` holds what the sweeps share. What a new figure
needs: ``docs/method-notes.md``.
"""

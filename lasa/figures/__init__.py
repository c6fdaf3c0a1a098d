"""One module per figure: its config, its tidy columns, ``run``, ``claims`` and ``plot``.

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
:mod:`.study`             the study's run (its Config)      11_eating_study
:mod:`.study_tests`       the study's tests                 11_eating_study
:mod:`.study_claims`      claims H1-H3                      11_eating_study
:mod:`.study_analysis`    completion, stuck, mode switches  11_eating_study
:mod:`.study_plots`       Figs. error, time, dessert        11_eating_study
========================  ================================  ===========================

Each figure module defines ``NAME`` (the figure's file stem under ``figures/``), ``COLUMNS``
(the columns of its CSV, one row per episode or measurement), a frozen ``Config`` built from
its notebook's ``settings`` (:func:`lasa.base.config.from_dict`) and ``plot`` (the whole figure,
every robot present). Those with claims (sims 1-4 and the study) define ``claims``, each
verdict's rule in its docstring; those that simulate define ``run`` (not
``entropy_ablation``, whose step is ``run_sweep``, nor ``eating_task``, whose is
``train_readings``). The study is five modules, one concept each (the table); it has three
figures, each a :class:`lasa.figures.study_plots.FigureSpec` (``GOAL_ERROR``, ``TIME``,
``ALIGNMENT``) with its own ``NAME``, ``COLUMNS`` and ``plot``. Two modules are no figure's own:
:mod:`.common`, what several figures share, and :mod:`.new_cups`, the episodes that sim4's ``run``
tabulates.
:func:`lasa.evidence.publish.publish` merges a robot's rows into the figure's CSV, redraws the
figure and updates the claims table, as one step under the folder lock. Changing a figure
means changing its module and its notebook; a new figure also needs its Make target and its
sections of ``configs/*.yaml`` (``docs/guide.md``).

The claims of sims 1-4 come with their uncertainty and one row per reading of shared
autonomy (:mod:`lasa.evidence.verdicts`); the verdict map re-evaluates the sim1-sim3 claims over
a grid of settings, and runs its cells locally or on a Dask cluster (:mod:`lasa.pipeline.scaleout`).

The decision rules of sims 1-4 were written before the results they judge were first seen,
with one exception, said where it stands: the "partly" rule of sim4's first claim was made
stricter after its first results (:func:`lasa.figures.sim4.claims`). The study's rules were
written after pilot runs of 4 and 10 participants, and its ``mean_distance`` reading after
the first paper-scale run (:mod:`lasa.figures.study_claims`).
"""

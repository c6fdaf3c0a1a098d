"""The eating study (notebook 11): :mod:`.run` (its Config and the cohort's run), :mod:`.claims` (H1-H3,
on :mod:`lasa.evidence.hypotheses`), :mod:`.analysis`, :mod:`.caps` (the belief's cap), :mod:`.plots`
and :mod:`.power` (who a replication needs)."""

"""The method: the decoder phi(z, s, b), its inference forward, its dataset and training, the
entropy term, the belief, shared autonomy's assistance and blend, the one control step, new goals,
and Retargeting.
"""

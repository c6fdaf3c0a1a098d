"""The method: the decoder phi(z, s, b), its inference forward, its dataset and training, the
entropy term, the belief, shared autonomy's members, the one control step and episode runner, the
context map of new goals, and Retargeting.
"""

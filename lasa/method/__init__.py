"""The method: the decoder phi(z, s, b) and its training, the belief, shared autonomy's members,
the control step and episode runner, the context map of new goals, and Retargeting."""

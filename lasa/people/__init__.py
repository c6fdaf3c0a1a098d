"""Simulated people: Boltzmann users and their rollout (sims 1-4), the demonstrator, the participants."""

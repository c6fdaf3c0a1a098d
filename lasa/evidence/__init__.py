"""The evidence: rules, claims, verdicts, statistics, metrics, plots, videos, the latent property."""

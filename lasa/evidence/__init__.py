"""The evidence: decision rules, claims and verdicts, statistics, metrics, plots, videos, the
latent-action property, and publishing a figure's rows.
"""

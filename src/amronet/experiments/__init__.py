"""Experiments: running many seeded runs, statistics, and the paper's figures."""

"""Test configuration: Hypothesis runs derandomized (seeded and reproducible) with no example database."""

from hypothesis import settings

settings.register_profile("mjtvm", derandomize=True, database=None, print_blob=True)
settings.load_profile("mjtvm")

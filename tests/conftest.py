"""Test configuration: Hypothesis runs derandomized (seeded and reproducible) with no example
database; MuJoCo renders headless with EGL, as ``mjtvm show --png`` sets it (MuJoCo picks its
GL back end when first imported, so it is set here, before any test module imports it)."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from hypothesis import settings

settings.register_profile("mjtvm", derandomize=True, database=None, print_blob=True)
settings.load_profile("mjtvm")

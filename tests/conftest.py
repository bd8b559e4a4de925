"""Test configuration: Hypothesis runs derandomized (seeded and reproducible) with no example
database; MuJoCo renders headless with EGL, as ``mjtvm show --png`` sets it (MuJoCo picks its
GL back end when first imported, so it is set here, before any test module imports it).
A suite started as a background job of a shell without job control (``cmd &`` in a script)
has SIGINT ignored, and children inherit an ignored signal across exec: the Ctrl-C tests'
``mjtvm`` processes would never see theirs. Python's own handler is restored here (a handler
is reset to the default on exec, so the children get SIGINT as a terminal gives it)."""

import os
import signal

if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

os.environ.setdefault("MUJOCO_GL", "egl")

from hypothesis import settings

settings.register_profile("mjtvm", derandomize=True, database=None, print_blob=True)
settings.load_profile("mjtvm")

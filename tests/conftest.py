"""Test-suite defaults: every scene runs on its own step module (the universal one only
where a test asks for it, tests/test_universal_step.py), and no run starts a background
compile."""

import os

os.environ.setdefault("DPM_KERNELS", "scene")
os.environ.setdefault("DPM_BACKGROUND_COMPILE", "0")

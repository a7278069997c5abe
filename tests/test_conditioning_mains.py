"""Tests of conditioning's 50/60 Hz hum checks (`_mains_problems`): the problem each branch exists for.

The rest of conditioning's tests are in tests/test_conditioning.py.
"""

from __future__ import annotations

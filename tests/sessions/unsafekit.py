"""The 1-D step-length config the tests of unsafe flags and of the recommended gait share: 15
(or ``num``) step lengths, the paper's 1-D model without jitter, self-sparring, seed 1, and an
``[safety] unsafe_radius``."""

from __future__ import annotations


def unsafe_config(name: str, radius: float, num: int = 15) -> str:
    """The config's TOML text, named ``name``, with ``num`` step lengths and ``radius``."""
    return f"""
name = "{name}"
[space.step_length]
min = 0.08
max = 0.18
num = {num}
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
jitter = 0.0
fit = "fixed"
[cospar]
seed = 1
strategy = "self-sparring"
[safety]
unsafe_radius = {radius}
"""

"""Numeric modules emitted by `symmech codegen` (numpy only; never edit by hand).

Installed as ``symmech.generated``. Regenerate with ``make codegen``; check with
``symmech codegen --check``.
"""

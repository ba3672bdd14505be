# symmech 0.1.0 generated module; inputs sha256 f0803fca1ecc361c7cd7e10d2adeae87ecc1fa8ae2d621a519715fc353a81745
# source key 0000000000000000000000000000000000000000000000000000000000000000
# body sha256 f0803fca1ecc361c7cd7e10d2adeae87ecc1fa8ae2d621a519715fc353a81745
"""Numeric modules emitted by `symmech codegen` (never edit by hand).

Installed as ``symmech.generated``: ``<name>.py`` needs numpy only (the
reference), ``<name>_nb.py`` is its numba twin (load it through
``symmech.core.kernels``). Regenerate with ``make codegen``; check with
``symmech codegen --check``. This index is written by codegen too.
"""

# spec name -> the derivation module that declares it (numpy module and _nb twin)
MODULES = {
    'grain_impact': 'symmech.grain.derive',
    'grain_impact_printed': 'symmech.grain.printed',
    'grain_motion': 'symmech.grain.derive_motion',
    'grain_motion_printed': 'symmech.grain.printed_motion',
    'smm_double_pendulum': 'symmech.smm.derive',
    'smm_excavator': 'symmech.smm.derive',
    'smm_formulas': 'symmech.smm.derive_formulas',
    'smm_printed': 'symmech.smm.printed',
    'smm_rotor_boom': 'symmech.smm.derive',
    'smm_spatial_boom': 'symmech.smm.derive',
    'trolley_dynamics': 'symmech.trolley.derive',
    'trolley_frame': 'symmech.trolley.derive',
    'trolley_printed': 'symmech.trolley.printed',
}
# derivation module -> data files and folders its derivation reads (relative to the checkout)
INPUTS = {
    'symmech.grain.derive': (),
    'symmech.grain.derive_motion': (),
    'symmech.grain.printed': (),
    'symmech.grain.printed_motion': (),
    'symmech.smm.derive': ('scenes', 'scenes/smm_double_pendulum.toml', 'scenes/smm_excavator.toml', 'scenes/smm_rotor_boom.toml', 'scenes/smm_spatial_boom.toml'),
    'symmech.smm.derive_formulas': (),
    'symmech.smm.printed': (),
    'symmech.trolley.derive': (),
    'symmech.trolley.printed': (),
}

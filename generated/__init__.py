# symmech 0.1.0 generated module; inputs sha256 b2ce09f583e9496c98f0c6b5058d1f9abe39dffb09dae96482b6ea217c03a38d
# source key 0000000000000000000000000000000000000000000000000000000000000000
# body sha256 b2ce09f583e9496c98f0c6b5058d1f9abe39dffb09dae96482b6ea217c03a38d
"""Numeric modules emitted by `symmech codegen` (never edit by hand).

Installed as ``symmech.generated``: ``<name>.py`` needs numpy only (the
reference), ``<name>_nb.py`` is its numba twin (load it through
``symmech.numerics.kernels``), ``<name>.c`` its C99 twin (``symmech export``
reads it through ``integrity.verify_file``). Regenerate with ``make codegen``; check with
``symmech codegen --check``. This index is written by codegen too; importing
it checks the body hash of every module of the package as it is imported.
"""
from symmech.core import integrity as _integrity

_integrity.guard(__file__)

# spec name -> the derivation module that declares it (numpy module, _nb and C twins)
MODULES = {
    'grain_impact': 'symmech.grain.derive',
    'grain_impact_printed': 'symmech.grain.printed',
    'grain_motion': 'symmech.grain.derive_motion',
    'grain_motion_printed': 'symmech.grain.printed_motion',
    'grain_sliding': 'symmech.grain.derive_sliding',
    'smm_double_pendulum': 'symmech.smm.derive',
    'smm_excavator': 'symmech.smm.derive',
    'smm_formulas': 'symmech.smm.derive_formulas',
    'smm_printed': 'symmech.smm.printed',
    'smm_rotor_boom': 'symmech.smm.derive',
    'smm_spatial_boom': 'symmech.smm.derive',
    'trolley_dynamics': 'symmech.trolley.derive',
    'trolley_elastic': 'symmech.trolley.elastic.derive',
    'trolley_elastic_lagrange': 'symmech.trolley.elastic.derive',
    'trolley_elastic_printed': 'symmech.trolley.elastic.printed',
    'trolley_frame': 'symmech.trolley.derive',
    'trolley_printed': 'symmech.trolley.printed',
}
# derivation module -> data files and folders its derivation reads (scenes/..., symmech/...)
INPUTS = {
    'symmech.grain.derive': (),
    'symmech.grain.derive_motion': (),
    'symmech.grain.derive_sliding': (),
    'symmech.grain.printed': (),
    'symmech.grain.printed_motion': (),
    'symmech.smm.derive': ('scenes', 'scenes/smm_double_pendulum.toml', 'scenes/smm_excavator.toml', 'scenes/smm_rotor_boom.toml', 'scenes/smm_spatial_boom.toml'),
    'symmech.smm.derive_formulas': (),
    'symmech.smm.printed': (),
    'symmech.trolley.derive': (),
    'symmech.trolley.elastic.derive': (),
    'symmech.trolley.elastic.printed': (),
    'symmech.trolley.printed': (),
}

"""symmech: symbolic derivations of three mechanics papers, emitted as numpy modules.

Importing the package is light: sympy is imported only by the derivation and
emission layers, never by the generated modules or their callers.

    import symmech
    result = symmech.load("scenes/smm_rotor_boom.toml").run()
    ds = result.to_xarray()            # labelled arrays with units
"""
__version__ = "0.1.0"


def load(source):
    """A validated scene from a TOML path or a dict (as TOML would give).

    ``scene = symmech.load("scenes/trolley_helix.toml")``: ``scene.kind.name``, the
    resolved fields ``scene.resolved``; ``result = scene.run()`` computes without
    writing files and returns a :class:`symmech.core.results.Result`
    (``result.summary``, ``result.tables``, ``result.to_xarray()``, ``result.event_log()``).
    A scene error raises :class:`symmech.core.scene.SceneError` naming the field.
    """
    from symmech.core.pipeline import load as _load

    return _load(source)

"""symmech: symbolic derivations of three mechanics papers, emitted as numpy modules.

Importing the package is light: sympy is imported only by the derivation and
emission layers, never by the generated modules or their callers.
"""
__version__ = "0.1.0"

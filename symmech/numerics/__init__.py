"""Compiled numerics: the ODE toolkit (one method per module), the generated twins and their build."""

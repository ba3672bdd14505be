"""jinja2 templates for `symmech codegen` (structure only; expressions come from the printer)."""

"""Paper 3 (seed 003): the structural model method (SMM) for lumped-parameter mechanisms."""

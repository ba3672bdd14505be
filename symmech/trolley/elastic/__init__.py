"""The elastic trolley (seed 002): beams and elastic rollers on the track frame, its Python reference and
compiled engine, its derivations and the scene's [elastic] table."""

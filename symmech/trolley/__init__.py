"""Paper 2 (seed 002): a two-axle trolley on a curved two-rail track."""

"""Paper 2 (seed 002): a two-axle trolley on a curved two-rail track."""

SEED = "002_7fa2a0a5477072ec"  # the seed file's stem: how every record names this paper


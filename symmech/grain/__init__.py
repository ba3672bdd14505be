"""Paper 1 (seed 000): an ellipsoidal grain bouncing on an inclined vibrating surface."""

SEED = "000_b52a2f612feb4113"  # the seed file's stem: how every record names this paper


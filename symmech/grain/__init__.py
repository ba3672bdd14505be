"""Paper 1 (seed 000): an ellipsoidal grain bouncing on an inclined vibrating surface."""

"""Sim-to-real gap diagnosis: where the reduced model departs from CFD, which unmodelled
effect causes it, and how far the gap shrinks once that effect is added."""

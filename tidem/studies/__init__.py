"""Runs of many variants: `tidem tradeoff` and `tidem sweep` (tradeoff) and `tidem bench` (bench).
Layer 7: may import runner/ and every layer below."""

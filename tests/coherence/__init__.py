"""Tests of refnpr.coherence against hand projections in float64 and naive loops."""

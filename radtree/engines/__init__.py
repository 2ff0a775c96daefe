"""Engines: take a scene, sky states and tracing parameters; return the tidy results table."""

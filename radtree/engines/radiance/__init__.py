"""The Radiance engine: writes an inspectable build folder and runs oconv/rtrace on it."""

//! Piecewise-constant 1D and 2D distributions over tabulated CDFs (light selection, environment map).

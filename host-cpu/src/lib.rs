//! fovea-cpu.

//! Watertight ray-triangle intersection (Woop, Benthin, Wald 2013).

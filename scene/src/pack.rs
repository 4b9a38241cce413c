//! Packing a loaded scene into core layout arrays.

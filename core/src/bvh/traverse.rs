//! Closest-hit and any-hit traversal with a fixed-size stack.

//! No library code: the oracle tests live in `tests/`.

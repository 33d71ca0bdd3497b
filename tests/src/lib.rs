//! Cross-crate integration tests of Lustre; the tests live in `tests/tests/`.

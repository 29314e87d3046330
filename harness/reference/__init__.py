"""Reference answers for situations the single-contact laws do not cover."""

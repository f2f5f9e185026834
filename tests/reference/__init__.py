"""Reference computations the tests compare the product against (no product path uses them)."""

"""nnik tests (a regular package, so that another distribution's top-level `tests` package, e.g. bCNC's, cannot shadow it)."""

"""Independent references the tests check the library against (closed forms derived apart from the code under test)."""

"""Text and JSON renderings of results, and the reproduction of the paper's worked examples."""

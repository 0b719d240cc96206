"""Simulated machines and warm-ups with their exact truth, for the tests and the benchmarks.

No command of mtident uses them: they are how its rules are measured. A user who wants to try a
rule on a machine of known physics may draw one here (:func:`~mtident.testing.warmups.random_warmup`).
"""

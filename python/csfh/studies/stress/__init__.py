"""The stiff and extreme cases: oracles, checks, cases, the suite that gives the verdicts, and
the report."""

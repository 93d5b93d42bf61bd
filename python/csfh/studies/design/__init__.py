"""Design for survival (`csfh design`): which hinge geometry passes a shock and stays precise.

A study (spec: a TOML file, built-in for the mems and csfh scenes) names design variables with
ranges, a shock condition and its directions, constraints (margins of the peak flexure stress
and contact pressure against their allowables) and objectives (peak stress, contacts, settling
time, parasitic motion under a nominal load). The designs are evaluated as shock runs through
the batch engine (evaluate), explored by quasi-random sampling, searched by differential
evolution (search), their sensitivities estimated by Sobol indices (sensitivity), and reported
(report) with the best designs written as scene files that `csfh shock` reproduces."""

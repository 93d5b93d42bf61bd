"""The studies: the paper's comparison (compare, paper_figures), error against run time (accuracy),
stiff and extreme cases (stress), the parametric sweep (sweep) and the tolerance Monte Carlo
(tolerance). Each computes apart from its report and figures."""

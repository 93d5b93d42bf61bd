"""The tolerance Monte Carlo: the study (file, sampling, tasks, analysis) and its report."""

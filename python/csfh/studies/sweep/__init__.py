"""The paper's parametric sweep: parameters, influence measure, tasks (spec), analysis, report and
figures."""

//! mtec-sensitivity: Global sensitivity analysis: EFAST, Sobol, Morris; test functions with analytic indices.

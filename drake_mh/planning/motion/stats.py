"""Statistics and outcomes of the compiled planners (``rrt_connect``, ``lazy_prm_star``): one
float64 array the kernels add to, indexed by these constants (counts first, then seconds when
profiling)."""

ITERATIONS, NODES, NN_SCANS, MOTIONS, STATES, BY_MARGIN, REFINED, REFINE_EVALS, REJECTED, BY_PROBES, \
    SHORTCUTS_TRIED, SHORTCUTS_KEPT, OUT_OF_DOMAIN, T_SAMPLE, T_NN, T_CHECK, T_CERTIFY, T_SHORTCUT, T_TOTAL, \
    T_FOUND = range(20)
STAT_NAMES = ("iterations", "nodes", "nn_scans", "motions", "states", "certified_by_margin", "refined",
              "refine_evals", "rejected", "rejected_by_probes", "shortcuts_tried", "shortcuts_kept", "out_of_domain",
              "t_sample", "t_nn", "t_check", "t_certify", "t_shortcut", "t_total", "t_found")
"""The names of the statistics, in index order (``info`` keys of
:func:`drake_mh.planning.rrt_connect.plan`)."""

FOUND, BUDGET, TIMEOUT = 0, 1, 2
"""Outcomes of a compiled plan: a path found, the budget spent, the deadline reached."""

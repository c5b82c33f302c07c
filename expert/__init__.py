"""expert: the paper's MILP task-and-motion planner on SCIP, its plans and the expert policy."""

"""The closed-loop evaluator: batched rollouts of any registered policy, per-episode logs
that survive interruption, success rates with Wilson intervals, tables, plots, videos."""

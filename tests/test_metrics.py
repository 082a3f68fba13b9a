"""The success interval always holds the observed rate (the chart's error bars rely on it)."""

from dexbench.eval.metrics import wilson_interval


def test_wilson_interval_holds_the_observed_rate_for_every_count():
    for n in range(1, 201):
        for k in range(n + 1):
            low, high = wilson_interval(k, n)
            assert 0.0 <= low <= k / n <= high <= 1.0, (k, n, low, high)

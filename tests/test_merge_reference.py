"""The paper's Table 3 as a reference column set: the numbers in
`conf/reference/dexverse_table3.yaml` are the paper's own (read from its LaTeX source when
it is beside the checkout), cover the baseline split, and `merge reference=` sets them
beside measured columns on the same tasks."""

from __future__ import annotations

import csv
import pathlib
import re

import pytest
from omegaconf import OmegaConf

from dexbench.cli.config import CONF_DIR, ConfigError
from dexbench.cli.merge import load_reference, merge
from dexbench.eval.merge import markdown, merge_runs
from dexbench.eval.metrics import summarize
from dexbench.eval.records import EpisodeRecord
from dexbench.eval.tables import write_tables

PAPER = pathlib.Path(__file__).resolve().parents[2] / "shared" / "seed" / "dexverse_paper.tex"


def test_reference_is_the_papers_table_3_on_the_baseline_split():
    ref = load_reference("dexverse_table3")
    assert ref.columns == ["pi0.5", "OpenVLA", "DP3", "DP"]
    split = OmegaConf.load(CONF_DIR / "split" / "baseline19.yaml")
    assert list(ref.tasks) == [t for ts in split.categories.values() for t in ts]
    means = [sum(v[i] for v in ref.tasks.values()) / len(ref.tasks) for i in range(4)]
    assert [round(m, 2) for m in means] == [0.34, 0.19, 0.34, 0.32]  # the paper's Mean row
    if not PAPER.exists():
        pytest.skip(f"{PAPER} not beside the checkout")
    table = PAPER.read_text().split(r"\label{tab:il-baseline-sr}")[1].split(r"\end{tabular}")[0]
    rows = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.rstrip("\\ ").split("&")]
        if len(cells) == 6 and cells[1] in ref.tasks:
            rows[cells[1]] = [float(re.sub(r"\\textbf\{(.*)\}", r"\1", c)) for c in cells[2:]]
    assert rows == ref.tasks


def _run(out: pathlib.Path, policy: str, wins: dict[str, int]) -> pathlib.Path:
    records = [EpisodeRecord(task=t, episode=i, seed=0, success=i < k, steps=10, time_s=0.1,
                             sim_warnings=0, embodiment="floating_shadow")
               for t, k in wins.items() for i in range(4)]
    summary = summarize({"Articulated": list(wins)}, records, {}, {
        "label": "demo", "policy": policy, "policy_label": policy, "episodes_per_task": 4})
    out.mkdir(parents=True)
    write_tables(summary, out)
    return out


def test_merge_sets_the_papers_columns_beside_ours(tmp_path):
    run = _run(tmp_path / "dp", "dp", {"OpenFaucet": 4, "OpenLaptop": 1})
    table = merge_runs([run], load_reference("dexverse_table3"))
    assert table.policies == ["dp", "pi0.5 (paper)", "OpenVLA (paper)", "DP3 (paper)",
                              "DP (paper)"]
    assert table.cells["OpenFaucet"]["DP (paper)"] == 0.28
    # the paper's means over the tasks we evaluated, not over its 19
    assert table.means["all"]["pi0.5 (paper)"] == pytest.approx((0.84 + 0.04) / 2)
    md = markdown(table)
    assert "| Articulated | OpenFaucet | **1.00** [0.51, 1.00] | 0.84 | 0.36 | 0.76 | 0.28 |" in md
    assert "Columns marked (paper): DexVerse paper, Table 3" in md
    assert merge([str(run), f"out={tmp_path / 'm'}", "reference=dexverse_table3"]) == 0
    header = next(csv.reader((tmp_path / "m/merged.csv").open()))
    assert header[2:] == [*table.policies, "dp ci_low", "dp ci_high"]
    with pytest.raises(ConfigError, match=r"reference=nope is not in conf/reference/; "
                                          r"references: \['dexverse_table3'\]"):
        merge([str(run), "reference=nope"])

"""Rule `diagnostics_records`: every record of the warnings' study at one true e, load and noise level, with its checks."""

import sys

from rockdec.studies import diagnostics_study
from rockdec import engine
from rockdec.pipeline import job
from rockdec.pipeline.layout import DIAGNOSTICS_PARTS


def main(smk):
    with engine.session(smk.threads):
        e, corner, noise = DIAGNOSTICS_PARTS[smk.wildcards.part]
        table = diagnostics_study.run(e_values=(e,), corners=(corner,), noise_levels=(noise,), cache_dir=smk.params.cache)
    cost = table.attrs
    print(
        f"checks' statistics {cost['statistics_s']:.1f} s, simulating and analysing {cost['simulate_analyse_s']:.1f} s "
        f"(ratio {cost['statistics_s'] / cost['simulate_analyse_s']:.4f}); {cost['calibrations']} calibrations",
        file=sys.stderr,
    )
    table.to_csv(smk.output[0], index=False)


if __name__ == "__main__":
    job.run(main, snakemake)

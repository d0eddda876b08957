"""Rule `campaign_table`: every record's and block's estimate side by side."""

from rockdec import io
from rockdec.pipeline import campaign, job


def main(smk):
    datasets = []
    for path in [*smk.input.records, *smk.input.blocks]:
        with io.open_dataset(path) as ds:
            datasets.append(ds.load())
    summary = campaign.summary_dataset(datasets)
    summary.attrs.update(io.provenance("campaign_table", {"units": list(smk.params.units)}))
    io.write_netcdf(summary, smk.output.nc)
    tab = campaign.table(summary)
    tab.to_csv(smk.output.csv, index=False)
    with open(smk.output.md, "w") as f:
        f.write(campaign.markdown(tab))


if __name__ == "__main__":
    job.run(main, snakemake)

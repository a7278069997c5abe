# ballimpact: force-platform tennis-ball impact tests (Goodwill & Haake 2004), raw sessions to
# results/<session_id>/ (impacts.csv, parameters.csv, <session_id>.nc, report.pdf, figures/);
# results/catalogue/ across sessions (catalogue.csv, catalogue.nc, catalogue.pdf).
#   snakemake --cores 2                                   every session of raw/
#   snakemake --cores 2 --config sessions=[s1]            one session
#   snakemake --profile profiles/slurm                    on a SLURM cluster
#   snakemake --report report.html                        HTML report of the figures

# config.yaml next to this Snakefile, whatever the working directory (--configfile adds to it)
configfile: os.path.join(workflow.basedir, "config.yaml")


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
wildcard_constraints:
    # "catalogue" is results/catalogue/ (workflow/rules/catalogue.smk), never a session
    session=r"(?!catalogue(?![A-Za-z0-9_.-]))[A-Za-z0-9][A-Za-z0-9_.-]*",
    chunk=r"[0-9]+",
    ball=r"[A-Za-z0-9_-]+",


include: "workflow/rules/process.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/session.smk"
include: "workflow/rules/summary.smk"
include: "workflow/rules/catalogue.smk"


rule all:
    input:
        [target for session in SESSIONS for target in session_targets(session)],
        CATALOGUE_TARGETS,

# Stage 4: the lab's catalogue across sessions (results/catalogue/), rebuilt whenever a
# session's archive or parameters.csv changes, a session is added, or config `pool` changes.

CATALOGUE_DIR = f"{RESULTS_DIR}/catalogue"
# A session folder named like the catalogue's folder would share its results folder.
if "catalogue" in SESSIONS:
    raise WorkflowError(
        f"session folder {RAW_DIR}/catalogue: the name 'catalogue' is reserved for "
        f"{CATALOGUE_DIR} (the catalogue across sessions); rename the session folder and its session_id"
    )
# sessions with a session-level fault have no results and stay out of the catalogue
CATALOGUE_SESSIONS = [s for s in SESSIONS if "fault" not in SESSION_INFO[s]]


POOLS = _check_pools(config.get("pool"))
CATALOGUE_TARGETS = (
    [f"{CATALOGUE_DIR}/catalogue.csv", f"{CATALOGUE_DIR}/catalogue.nc", f"{CATALOGUE_DIR}/catalogue.pdf"]
    if CATALOGUE_SESSIONS
    else []
)


rule catalogue:
    """catalogue.csv, catalogue.nc, catalogue.pdf: every session x ball type, change tests, pooled fits, ranking."""
    input:
        archives=[f"{RESULTS_DIR}/{s}/{s}.nc" for s in CATALOGUE_SESSIONS],
        parameters=[f"{RESULTS_DIR}/{s}/parameters.csv" for s in CATALOGUE_SESSIONS],
    output:
        csv=f"{CATALOGUE_DIR}/catalogue.csv",
        nc=f"{CATALOGUE_DIR}/catalogue.nc",
        pdf=report(
            f"{CATALOGUE_DIR}/catalogue.pdf",
            caption="../report/catalogue_pdf.rst",
            category="Catalogue",
            labels={"figure": "catalogue.pdf", "shows": "every session x ball type, changes, ranking"},
        ),
    params:
        session_dirs=[f"{RESULTS_DIR}/{s}" for s in CATALOGUE_SESSIONS],
        pool=POOLS,
        n_bootstrap=config["bootstrap"],
        seed=config["seed"],
    conda:
        "../envs/ballimpact.yaml"
    log:
        f"{CATALOGUE_DIR}/logs/catalogue.log",
    benchmark:
        f"{CATALOGUE_DIR}/benchmarks/catalogue.tsv"
    threads: 1
    script:
        "../scripts/catalogue.py"

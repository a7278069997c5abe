# Stage 3: figures and the PDF report of a session.


rule figures:
    """Every report figure as its own PNG, plus one QC page per excluded impact in figures/qc/."""
    input:
        archive=result_path("{session}.nc"),
    output:
        # one output per figure of the registry (ballimpact.figure_registry), named by its
        # stem, and the QC folder (figure_outputs, common.smk)
        **figure_outputs(),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("figures"),
    benchmark:
        benchmark_path("figures")
    threads: 1
    script:
        "../scripts/figures.py"


rule report:
    """The session report (report.pdf) from the archive and the figures."""
    input:
        archive=result_path("{session}.nc"),
        figures=[result_path(f"figures/{fig.file_name}") for fig in REPORT_FIGURES],
        qc=result_path(f"figures/{QC_DIR_NAME}"),
    output:
        pdf=report_pdf_output(),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("report"),
    benchmark:
        benchmark_path("report")
    threads: 1
    script:
        "../scripts/report.py"

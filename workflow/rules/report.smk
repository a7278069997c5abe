# Stage 3: figures and the PDF report of a session.


rule figures:
    """Every report figure as its own PNG, plus one QC page per excluded impact in figures/qc/."""
    input:
        archive=result_path("{session}.nc"),
    output:
        # one output per figure of the registry (ballimpact.figure_registry), named by its stem
        **{
            fig.stem: report(
                result_path(f"figures/{fig.file_name}"),
                caption=f"../report/{fig.stem}.rst",
                category=fig.category,
                subcategory="{session}",
                labels={"session": "{session}", "figure": fig.report_label, "shows": fig.shows},
            )
            for fig in REPORT_FIGURES
        },
        qc=report(
            directory(result_path(f"figures/{QC_DIR_NAME}")),
            patterns=["{name}.png"],
            caption="../report/qc.rst",
            category="Quality control",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "QC {name}", "shows": "raw trace of an excluded impact"},
        ),
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
        pdf=report(
            result_path("report.pdf"),
            caption="../report/report_pdf.rst",
            category="Session report",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "report.pdf", "shows": "the whole session report"},
        ),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("report"),
    benchmark:
        benchmark_path("report")
    threads: 1
    script:
        "../scripts/report.py"

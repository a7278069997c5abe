# Stage 3: figures and the PDF report of a session.


rule figures:
    """Every report figure as its own PNG, plus one QC page per excluded impact in figures/qc/."""
    input:
        archive=result_path("{session}.nc"),
    output:
        fig7_contact_time_cor=report(
            result_path("figures/fig7_contact_time_cor.png"),
            caption="../report/fig7_contact_time_cor.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "Fig. 7", "shows": "contact time and COR vs inbound speed"},
        ),
        cor_speed_itf=report(
            result_path("figures/cor_speed_itf.png"),
            caption="../report/cor_speed_itf.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "COR 3-40 m/s", "shows": "COR vs speed, extrapolation, ITF drop test"},
        ),
        fig8_stiffness=report(
            result_path("figures/fig8_stiffness.png"),
            caption="../report/fig8_stiffness.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "Fig. 8", "shows": "structural stiffness vs displacement"},
        ),
        fig9_force_curves=report(
            result_path("figures/fig9_force_curves.png"),
            caption="../report/fig9_force_curves.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "Fig. 9", "shows": "measured and modelled force curves"},
        ),
        fig10_components=report(
            result_path("figures/fig10_components.png"),
            caption="../report/fig10_components.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "Fig. 10", "shows": "force components at 20 m/s"},
        ),
        fig2b_kelvin_voigt=report(
            result_path("figures/fig2b_kelvin_voigt.png"),
            caption="../report/fig2b_kelvin_voigt.rst",
            category="Model fit",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "Fig. 2b", "shows": "Kelvin-Voigt model vs measurement"},
        ),
        kcal=report(
            result_path("figures/kcal.png"),
            caption="../report/kcal.rst",
            category="Calibration",
            subcategory="{session}",
            labels={"session": "{session}", "figure": "kCAL", "shows": "calibration factor per impact"},
        ),
        qc=report(
            directory(result_path("figures/qc")),
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
        figures=expand(result_path("figures/{stem}.png"), stem=FIGURES, allow_missing=True),
        qc=result_path("figures/qc"),
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

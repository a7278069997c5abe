"""The report figures of a session, listed once: stem, title, caption, height, draw function, report entry."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "QC_DIR_NAME",
    "PAGES",
    "ReportFigure",
    "REPORT_FIGURES",
    "FIGURE_STEMS",
    "rows_height_in",
    "report_figure",
]

#: Sub-folder of the figures folder with one QC page (PNG) per excluded impact.
QC_DIR_NAME = "qc"
#: Where a figure stands in the PDF report: ``own`` (a page of its own, with its caption) or ``rig`` (on the
#: rig page, :mod:`ballimpact.report_rig`, beside the table of the session's rig).
PAGES = ("own", "rig")


def rows_height_in(n_rows: int, per_row_in: float, extra_in: float = 0.7, cap_in: float = 10.0) -> float:
    """Height of a figure with ``n_rows`` rows of panels [in]: ``per_row_in`` [in] a row plus
    ``extra_in`` [in] for the title, at most ``cap_in`` [in] (so that it fits an A4 page)."""
    return min(per_row_in * max(n_rows, 1) + extra_in, cap_in)


@dataclass(frozen=True)
class ReportFigure:
    """One report figure: a PNG of every session, a page of its PDF report and an entry of the Snakemake report.

    Attributes
    ----------
    stem : str
        File name without ``.png``; also the name of the figures rule's output and of
        its Snakemake report caption ``workflow/report/<stem>.rst``.
    draw_name : str
        Function of :mod:`ballimpact.figures` that draws it into a matplotlib figure,
        ``draw(fig, ds)``.
    title, caption : str
        Title and caption on its page of the PDF report.
    layout : str
        ``per_ball`` (one row of panels per ball type), ``two_columns`` (one panel per
        ball type, two columns) or ``fixed``.
    height_in : float
        Height of a row of panels [in] (``per_ball``, ``two_columns``) or of the
        figure (``fixed``) [in].
    category, report_label, shows : str
        Category and labels of its entry in the Snakemake report.
    page : str
        Where it stands in the PDF report: ``own`` (a page of its own) or ``rig`` (on the rig page), one of
        :data:`PAGES`.
    module : str
        Module of ``ballimpact`` that defines ``draw_name`` (``figures``, ``figures_model`` for the model's
        figures, or ``figures_rig`` for the rig's).
    """

    stem: str
    draw_name: str
    title: str
    caption: str
    layout: str
    height_in: float
    category: str
    report_label: str
    shows: str
    page: str = "own"
    module: str = "figures"

    def __post_init__(self):
        if self.layout not in ("per_ball", "two_columns", "fixed"):
            raise ValueError(f"figure {self.stem}: layout must be per_ball, two_columns or fixed, got {self.layout!r}")
        if self.page not in PAGES:
            raise ValueError(f"figure {self.stem}: page must be one of {', '.join(PAGES)}, got {self.page!r}")

    @property
    def file_name(self) -> str:
        """PNG file name in the session's figures folder."""
        return f"{self.stem}.png"

    def figure_height_in(self, n_balls: int) -> float:
        """Height of the figure [in] for a session with ``n_balls`` ball types."""
        if self.layout == "per_ball":
            return rows_height_in(n_balls, self.height_in)
        if self.layout == "two_columns":
            return rows_height_in(-(-n_balls // 2) if n_balls > 1 else 1, self.height_in)
        return self.height_in

    @property
    def draw(self):
        """The draw function ``draw(fig, ds)`` of its module (:mod:`ballimpact.figures` unless ``module`` says
        otherwise; imported on first use)."""
        import importlib

        return getattr(importlib.import_module(f"{__package__}.{self.module}"), self.draw_name)


_MODEL_FIT = "Model fit"

#: Every report figure in report order.
REPORT_FIGURES: tuple[ReportFigure, ...] = (
    ReportFigure(
        stem="fig7_contact_time_cor",
        draw_name="draw_contact_time_cor",
        title="Contact time and coefficient of restitution against inbound speed",
        caption=(
            "Each row is one ball type. Circles are the good impacts of this session (contact time TC from "
            "the force trace, COR = VB'/VB from the light gates); the black line is the improved model "
            "(Eq. 14 of Goodwill & Haake 2004) with the parameters fitted to these impacts, the shaded "
            "area its 95 % confidence band (where the curve lies, from the parameter uncertainty) and the "
            "dashed lines the 95 % prediction band (where the next impact of this ball type will fall: "
            "parameter uncertainty plus the impacts' own scatter). Red crosses are fit outliers: good "
            "impacts left out of the fit because they sit far off their siblings' curve (listed with their "
            "residuals among the excluded impacts). TC is set by the stiffness law (AK, a), COR mainly by "
            "the damping constant AC. The paper reports agreement within about 5 %. The grey shading marks "
            "the speeds of the impacts fitted; outside it the curves are dashed: the model extrapolates there."
        ),
        layout="per_ball",
        height_in=2.3,
        category=_MODEL_FIT,
        report_label="Fig. 7",
        shows="contact time and COR vs inbound speed",
        module="figures_model",
    ),
    ReportFigure(
        stem="cor_speed_itf",
        draw_name="draw_cor_speed_range",
        title="COR from 3 to 40 m/s, where the model stops, and the ITF drop test",
        caption=(
            "Each panel is one ball type. The fitted model COR (Eq. 14) is solid over the speeds of the impacts "
            "it was fitted on (shaded) and dashed where it extrapolates, with its 95 % band; circles are the "
            "good impacts. At the impact speed of the ITF drop test (254 cm onto a rigid surface, about 6.9 m/s "
            "with air drag; Cd 0.55, air density from session.yaml, default 1.2 kg/m³) the diamond is the "
            "model, the green bar the ITF pass range 134.6-147.3 cm as a COR, and the red star the measured "
            "drop test when session.yaml gives itf_rebound_cm. The model's material damping cB = AC dCONT² "
            "vanishes at small deformation, so below the fitted speeds it over-predicts COR; for the paper's "
            "own Table 2 parameters and Table 1 drop tests the model is 0.07-0.10 too high."
        ),
        layout="two_columns",
        height_in=3.2,
        category=_MODEL_FIT,
        report_label="COR 3-40 m/s",
        shows="COR vs speed, extrapolation, ITF drop test",
        module="figures_model",
    ),
    ReportFigure(
        stem="fig8_stiffness",
        draw_name="draw_stiffness",
        title="Structural stiffness against centre-of-mass displacement",
        caption=(
            "kB = kB(0) + AK x^a (Eq. 4) for every ball type: solid lines use the parameters fitted here, "
            "dashed lines the values of the paper's Table 2 (Table 2 ball types only). A stiffer ball has a "
            "higher curve; the pressurised ball is the stiffest in the paper, the punctured ball is soft at "
            "small displacements and stiffens quickly. Ball types without a fit are listed in the panel."
        ),
        layout="fixed",
        height_in=5.2,
        category=_MODEL_FIT,
        report_label="Fig. 8",
        shows="structural stiffness vs displacement",
        module="figures_model",
    ),
    ReportFigure(
        stem="fig9_force_curves",
        draw_name="draw_force_curves",
        title="Measured and modelled force at the lowest and highest good speed",
        caption=(
            "For each ball type, the good impacts at the lowest and highest inbound speed: force against time "
            "(left) and against centre-of-mass displacement (right, from integrating the force twice). "
            "Solid: measured; dashed: the fitted model simulated at the same speed. The model force is zero "
            "below 2 mm (cloth) and uses the pre-buckling stiffness for the first 0.2 ms; after that the "
            "paper finds model and measurement within about 10 %."
        ),
        layout="per_ball",
        height_in=2.4,
        category=_MODEL_FIT,
        report_label="Fig. 9",
        shows="measured and modelled force curves",
        module="figures_model",
    ),
    ReportFigure(
        stem="fig10_components",
        draw_name="draw_components",
        title="Force components of the fitted model at 20 m/s",
        caption=(
            "The total model force split into structural stiffness kB x, material damping cB x' and "
            "momentum flux cM x' (Eq. 14), simulated at 20 m/s with each ball's fitted parameters; grey is "
            "the measured good impact nearest 20 m/s (within 2.5 m/s). The paper finds the momentum flux "
            "dominant during the first 0.6 ms (shaded) and the stiffness term dominant at the force peak; "
            "the damping term turns negative in restitution."
        ),
        layout="two_columns",
        height_in=3.2,
        category=_MODEL_FIT,
        report_label="Fig. 10",
        shows="force components at 20 m/s",
        module="figures_model",
    ),
    ReportFigure(
        stem="fig2b_kelvin_voigt",
        draw_name="draw_kelvin_voigt",
        title="Kelvin-Voigt model against the measured force",
        caption=(
            "The fastest good impact of each ball type (solid) against the linear Kelvin-Voigt model with "
            "kB = m pi^2 / TC^2 and cB = -2 m ln(COR) / TC (Eqs 1-3, dashed) and the improved model (dotted). "
            "The Kelvin-Voigt force starts at cB VB instead of zero and turns tensile (shaded) before the "
            "ball leaves the plate, the failure shown in Fig. 2b of the paper that motivates the improved model."
        ),
        layout="two_columns",
        height_in=3.2,
        category=_MODEL_FIT,
        report_label="Fig. 2b",
        shows="Kelvin-Voigt model vs measurement",
        module="figures_model",
    ),
    ReportFigure(
        stem="kcal",
        draw_name="draw_kcal",
        title="Per-impact force-plate calibration factor",
        caption=(
            "kCAL = m (VB + VB') / integral of V dt for every impact in the order of the raw impacts.csv, "
            "coloured by ball type. The line is the session median over the good impacts and the grey band "
            "median +- 3 robust standard deviations. A drift or a step suggests a change in the charge "
            "amplifier or plate; a single outlier points to a bad gate time or trace. Excluded impacts are "
            "crossed when they have a kCAL and marked on the axis when they do not."
        ),
        layout="fixed",
        height_in=4.6,
        category="Calibration",
        report_label="kCAL",
        shows="calibration factor per impact",
    ),
    ReportFigure(
        stem="rig_ringing",
        draw_name="draw_rig_ringing",
        title="The plate's free ringing after every contact, pooled",
        caption=(
            "After the ball leaves, the plate rings freely at its first resonance. Grey: the ringing after each "
            "contact whose ringing was fitted (plate_impacts), its baseline (a cubic and the mains harmonics, "
            "fitted jointly) removed, divided by its fitted amplitude and shifted by its fitted phase, so that "
            "every impact falls on one curve; black: the damped response of the session's resonance "
            "exp(-zeta wn t) cos(wd t), dashed its envelope. Grey that leaves the black curve means a resonance "
            "that is not the session's. Without an identified or stated plate the panel says why."
        ),
        layout="fixed",
        height_in=3.0,
        category="Rig",
        report_label="Plate ringing",
        shows="pooled free ringing and the session's plate resonance",
        page="rig",
        module="figures_rig",
    ),
    ReportFigure(
        stem="rig_per_impact",
        draw_name="draw_rig_per_impact",
        title="Amplifier time constant and kCAL of every impact against the session's",
        caption=(
            "Left: the charge amplifier's time constant estimated from each impact's trace, with its 95 % bar "
            "(2 standard errors); right: each impact's kCAL with its 95 % bar (2 standard uncertainties), both "
            "against the impact's place in the raw impacts.csv. The line is the session's value (rig_value: "
            "identified from all impacts, or stated in session.yaml), the band its 95 % interval. Impacts "
            "excluded are red crosses; impacts kept but not pooled (kCAL withheld) are open circles."
        ),
        layout="fixed",
        height_in=3.0,
        category="Rig",
        report_label="Rig per impact",
        shows="time constant and kCAL per impact vs the session's values",
        page="rig",
        module="figures_rig",
    ),
)

#: PNG file stems of the report figures, in report order.
FIGURE_STEMS: tuple[str, ...] = tuple(f.stem for f in REPORT_FIGURES)


def report_figure(key: str) -> ReportFigure:
    """The report figure with this stem, PNG file name or draw function name; KeyError when none."""
    for fig in REPORT_FIGURES:
        if key in (fig.stem, fig.file_name, fig.draw_name):
            return fig
    raise KeyError(f"no report figure {key!r}; the figures are {list(FIGURE_STEMS)}")

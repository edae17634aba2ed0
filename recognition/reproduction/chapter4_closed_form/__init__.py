"""Fig. 4.5, Tables 4.2, 4.3 and 4.5 and Figs. 4.3 and 4.7 of the thesis (closed forms).

:mod:`.experiments` holds the settings and the data (noisy data curves through a point
of a Table 4.1 surface or a Fig. 4.15 solid, the 40 recognition tests), :mod:`.reference`
the thesis's printed values, :mod:`.tables` the reproduced tables and :mod:`.figures`
the figures.
"""

from recognition.reproduction.chapter4_closed_form.experiments import (
    LONG_CURVES,
    SAMPLE_DOMAINS,
    SURFACES,
    SolidExperiment,
    SurfaceExperiment,
    default_experiment,
    noisy_data_curves,
    surface_instances,
    tilted_plane_normals,
)
from recognition.reproduction.chapter4_closed_form.figures import figures
from recognition.reproduction.chapter4_closed_form.reference import (
    FIG_4_5_THESIS,
    TABLE_4_2_THESIS,
    TABLE_4_3_THESIS,
    TABLE_4_5_THESIS,
)
from recognition.reproduction.chapter4_closed_form.tables import (
    fig_4_5,
    table_4_2,
    table_4_3,
    table_4_5,
)

__all__ = [
    "FIG_4_5_THESIS",
    "LONG_CURVES",
    "SAMPLE_DOMAINS",
    "SURFACES",
    "TABLE_4_2_THESIS",
    "TABLE_4_3_THESIS",
    "TABLE_4_5_THESIS",
    "SolidExperiment",
    "SurfaceExperiment",
    "default_experiment",
    "fig_4_5",
    "figures",
    "noisy_data_curves",
    "surface_instances",
    "table_4_2",
    "table_4_3",
    "table_4_5",
    "tilted_plane_normals",
]

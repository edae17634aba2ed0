"""The values the thesis prints in Fig. 4.5 and Tables 4.2, 4.3 and 4.5 (closed forms)."""

from __future__ import annotations

from typing import Any

__all__ = ["FIG_4_5_THESIS", "TABLE_4_2_THESIS", "TABLE_4_3_THESIS", "TABLE_4_5_THESIS"]

TABLE_4_2_THESIS: dict[str, dict[str, float]] = {
    "min_distance": {
        "ellipsoid": 0.0169,
        "elliptic_paraboloid": 0.0148,
        "monkey_saddle": 0.0053,
        "crossed_trough": 0.0171,
    },
    "max_distance": {
        "ellipsoid": 0.0408,
        "elliptic_paraboloid": 0.0448,
        "monkey_saddle": 0.0433,
        "crossed_trough": 0.0396,
    },
    "avg_distance": {
        "ellipsoid": 0.0288,
        "elliptic_paraboloid": 0.0297,
        "monkey_saddle": 0.0234,
        "crossed_trough": 0.0265,
    },
}

TABLE_4_3_THESIS: dict[str, Any] = {
    "decided_at_lookup": {
        "ellipsoid": 2,
        "elliptic_paraboloid": 1,
        "monkey_saddle": 9,
        "crossed_trough": 0,
    },
    "decided_by_local_search": {
        "ellipsoid": 8,
        "elliptic_paraboloid": 9,
        "monkey_saddle": 1,
        "crossed_trough": 10,
    },
    "successes": {
        "ellipsoid": 10,
        "elliptic_paraboloid": 10,
        "monkey_saddle": 10,
        "crossed_trough": 10,
    },
    "tests": {
        "ellipsoid": 10,
        "elliptic_paraboloid": 10,
        "monkey_saddle": 10,
        "crossed_trough": 10,
    },
    "wrong_model_error_excess_percent": 180.0,
}

FIG_4_5_THESIS: dict[str, Any] = {
    "point_uv": [1.21, 0.43],
    "normal": [0.1611, 0.5764, 0.8011],
    "k1": 0.9548,
    "k2": 0.6370,
    "true_k1": 0.9074,
    "true_k2": 0.6519,
    "candidates_uv": [[1.26, 0.4], [1.41, 0.4], [0.63, 0.5]],
    "candidate_errors": [0.000888, 0.000961, 0.001654],
    "local_minima_uv": [[1.26, 0.44], [1.27, 0.44], [1.17, 0.44]],
    "local_minima_errors": [0.000662, 0.000666, 0.000686],
    "estimate_uv": [1.26, 0.44],
}

TABLE_4_5_THESIS: dict[str, Any] = {
    "min_error_mm": {
        "cylinder_1": {
            "cylinder_1": 0.033,
            "cylinder_2": 0.182,
            "elliptic_cylinder": 0.230,
            "sphere": 0.271,
        },
        "cylinder_2": {
            "cylinder_1": 0.155,
            "cylinder_2": 0.072,
            "elliptic_cylinder": 0.224,
            "sphere": 0.306,
        },
        "elliptic_cylinder": {
            "cylinder_1": 0.446,
            "cylinder_2": 0.195,
            "elliptic_cylinder": 0.156,
            "sphere": 0.929,
        },
        "sphere": {
            "cylinder_1": 0.296,
            "cylinder_2": 1.056,
            "elliptic_cylinder": 0.254,
            "sphere": 0.055,
        },
    },
    "diagonal_minimum_in_every_column": True,
}

"""Registration of three data curves on models, and recognition by it (thesis 4.1.2-4.3.3).

One front door, :func:`register` (one model) / :func:`register_all` (several) /
:func:`recognize` (ranked, Eq. (4.9)); the config's class names the mode:

``FastConfig`` (default, mesh models)
    Every model's candidate poses screened in one batch on distance fields, refined by
    batched Gauss-Newton, polished on exact closest points (:mod:`.fast`).
``ThesisConfig`` (mesh models)
    The thesis's superposition by plane sections (4.15) and greedy 1-ring walk (4.16)
    (:mod:`.thesis`).
``IcpConfig`` (mesh models)
    Multi-start point-to-plane ICP, the practitioner's baseline (:mod:`.icp`).
``ClosedFormConfig`` (closed-form models)
    Local searches of E(u, v, phi) (4.11) from the table's candidates (:mod:`.closed_form`).
"""

from recognition.surfaces.registration.candidates import CandidateIndex
from recognition.surfaces.registration.config import (
    ALIGNED_SEARCH,
    THOROUGH_SEARCH,
    ClosedFormConfig,
    DataGeometryConfig,
    FastConfig,
    FastSearchConfig,
    IcpConfig,
    Optimizer,
    RegistrationConfig,
    ThesisConfig,
)
from recognition.surfaces.registration.data import (
    acceptable_error_m,
    common_point,
    data_fit_residual_m,
    data_geometry,
    data_noise_m,
    outlier_threshold_m,
)
from recognition.surfaces.registration.dispatch import (
    CONFIGS,
    Model,
    config_for,
    recognize,
    register,
    register_all,
    registration_mode,
)
from recognition.surfaces.registration.exact import (
    exact_error_m,
    polish,
    refine_exact,
    with_exact_error,
)
from recognition.surfaces.registration.ranking import Recognition, rank
from recognition.surfaces.registration.result import (
    ClosedFormRegistration,
    Registration,
    RegistrationMode,
    RegistrationStatus,
)

__all__ = [
    "ALIGNED_SEARCH",
    "CONFIGS",
    "THOROUGH_SEARCH",
    "CandidateIndex",
    "ClosedFormConfig",
    "ClosedFormRegistration",
    "DataGeometryConfig",
    "FastConfig",
    "FastSearchConfig",
    "IcpConfig",
    "Model",
    "Optimizer",
    "Recognition",
    "Registration",
    "RegistrationConfig",
    "RegistrationMode",
    "RegistrationStatus",
    "ThesisConfig",
    "acceptable_error_m",
    "common_point",
    "config_for",
    "data_fit_residual_m",
    "data_geometry",
    "data_noise_m",
    "exact_error_m",
    "outlier_threshold_m",
    "polish",
    "rank",
    "recognize",
    "refine_exact",
    "register",
    "register_all",
    "registration_mode",
    "with_exact_error",
]

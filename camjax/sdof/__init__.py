"""The one engine of the linear single-degree-of-freedom response, on every linear path.

The SDOF ``e'' + 2 zeta w e' + w^2 e = a(t)`` (``e`` the transmission's deflection, ``a``
a piecewise-smooth forcing) is one complex mode ``q = e' - conj(lambda) e`` with
``q' = lambda q + a``.  This package solves it once for everyone: the normalised rise of
``camjax.SpringMass`` and its sweeps (``camjax.ct_curve``), the design objectives, the
studies, and a cam program's turn at machine speed (``camjax.program``):

- the grid of any piecewise forcing over an interval (``piecewise_grid``; a law's rise:
  ``motion_grid``, ``SampledLaw``; a turn cut into segments: ``segment_layout``), with its
  degree-5 interpolant on every interval, sized by one policy (``default_resolution``: the
  phase step ``w h``) and refused past ``MAX_GRID_INTERVALS`` by one check
  (``check_grid_size``, the caller's words for what to change);
- the exact step over the grid from rest or a given state (``propagate``), the periodic
  steady state (``periodic_propagate``) and the exact state between nodes
  (``mode_between``);
- outputs ``Re(G q)`` and their refined peaks (``peak_in_motion``, bounded or dense:
  ``PEAK_SEARCHES``, chosen by ``SpringMassOptions.peak_search``, with ``plateau_bound`` on constant-acceleration intervals;
  ``refined_extremes``), the dwell's peak and the residual vibration;
- the same equation through diffrax (``integrate``, ``sdof_term``);
- host-side searches on exact values, a batch a round (``narrowed_crossing``,
  ``first_roots``, ``polished_maxima``): the program's jump speed, separations,
  re-impacts and peak forces;
- one chunked vmap for batches (``chunked_map``), its chunks sized by backend
  (``chunk_nodes``, ``stack_laws``; their sizes ``CHUNK_NODES`` on a CPU,
  ``ACCELERATOR_CHUNK_NODES`` and ``ACCELERATOR_STACK_EVALUATIONS`` elsewhere by default,
  a call's ``camjax.sharding.SweepOptions`` to tune a device).
"""

from ._batch import ACCELERATOR_CHUNK_NODES as ACCELERATOR_CHUNK_NODES
from ._batch import ACCELERATOR_STACK_EVALUATIONS as ACCELERATOR_STACK_EVALUATIONS
from ._batch import CHUNK_NODES as CHUNK_NODES
from ._batch import chunk_nodes as chunk_nodes
from ._batch import chunked_map as chunked_map
from ._batch import map_in_chunks as map_in_chunks
from ._batch import stack_laws as stack_laws
from ._grid import GAUSS_POINTS as GAUSS_POINTS
from ._grid import INTERPOLATION_DEGREE as INTERPOLATION_DEGREE
from ._grid import MAX_GRID_INTERVALS as MAX_GRID_INTERVALS
from ._grid import MAX_PHASE_STEP as MAX_PHASE_STEP
from ._grid import SAMPLED_LAWS_KEPT as SAMPLED_LAWS_KEPT
from ._grid import SEGMENT_MINIMUM as SEGMENT_MINIMUM
from ._grid import SEGMENT_PIECE_MINIMUM as SEGMENT_PIECE_MINIMUM
from ._grid import SEGMENTED_MINIMUM as SEGMENTED_MINIMUM
from ._grid import SUBSTEPS_PER_INTERVAL as SUBSTEPS_PER_INTERVAL
from ._grid import TARGET_PHASE_STEP as TARGET_PHASE_STEP
from ._grid import GridSegment as GridSegment
from ._grid import MotionGrid as MotionGrid
from ._grid import SampledLaw as SampledLaw
from ._grid import SegmentLayout as SegmentLayout
from ._grid import check_grid_size as check_grid_size
from ._grid import default_resolution as default_resolution
from ._grid import law_value_key as law_value_key
from ._grid import motion_grid as motion_grid
from ._grid import period_ratio_reach as period_ratio_reach
from ._grid import piecewise_grid as piecewise_grid
from ._grid import segment_layout as segment_layout
from ._grid import to_monomial as to_monomial
from ._ode import integrate as integrate
from ._ode import sdof_term as sdof_term
from ._ode import vector_field as vector_field
from ._peaks import PEAK_SEARCHES as PEAK_SEARCHES
from ._peaks import checked_peak_search as checked_peak_search
from ._peaks import deflection_gains as deflection_gains
from ._peaks import dwell_peak as dwell_peak
from ._peaks import gain_derivatives as gain_derivatives
from ._peaks import mode_gain as mode_gain
from ._peaks import output_jets as output_jets
from ._peaks import peak_in_motion as peak_in_motion
from ._peaks import plateau_bound as plateau_bound
from ._peaks import refined_extremes as refined_extremes
from ._peaks import refined_max as refined_max
from ._peaks import residual_amplitude as residual_amplitude
from ._peaks import residual_of_mode as residual_of_mode
from ._search import first_roots as first_roots
from ._search import narrowed_crossing as narrowed_crossing
from ._search import polished_maxima as polished_maxima
from ._step import eigenvalue as eigenvalue
from ._step import mode_between as mode_between
from ._step import periodic_propagate as periodic_propagate
from ._step import propagate as propagate
from ._step import psi as psi
from ._step import psi_host as psi_host
from ._step import series_kicks as series_kicks
from ._step import step_within_host as step_within_host
from ._step import steps_within as steps_within

"""Whole cams: motion programs in physical units, steady state at machine speed, jump, export.

``Program`` reads and checks a cam (segments over 360 degrees, follower in mm, N, kg);
``analyse`` reports the periodic steady state, contact force, minimum preload, jump speed,
every flight of a turn (``flights``) and a grooved cam's strikes (``groove_turns``) over a
list of speeds; ``response`` gives the histories over one turn at one speed; ``profile``,
``write_csv`` and ``write_dxf`` export the cam's shape (roller or flat face) and
``lift_from_dxf`` (``Program.from_dxf``) reads a drawn profile back as its lift; ``analyse``
also sizes the drive (torque, energy, flywheel), the Hertz contact stress and the cam's
``Geometry``; ``write_report`` writes a report's files (``summary.json``, ``response.csv``,
the profile, the figures); ``analyse_machine`` adds the torques of several cams on one shaft
(``Machine``); ``write_drive_table`` writes the motion as servo drives load it
(``drive_table``, ``read_drive_table``); ``design_segment`` designs one segment's law (``MaxPreload``: the least
preload over a speed range).  ``Chain`` is the follower as a chain of bodies (a valve
train, a spring that surges, or bodies on a swinging follower's flexible ``Arm``); ``Oscillator`` is the follower's modes in physical units,
the classic one-body follower's or a chain's, which ``SteadyState`` takes alike; a
servo's ``Drive`` and ``Motor`` give the motor's torque over the turn (``duty_cycle``,
``size_motor``, ``choose_motor`` from a catalogue, ``program_motor_choice`` at a program's
speeds), and ``compensate`` the cam lift that
makes the payload follow its law at one speed.  The equations are in docs/program.md,
docs/machine.md, docs/valve-trains.md and docs/servo.md.
"""

from typing import TYPE_CHECKING

from ._arm import ARM_FIELDS as ARM_FIELDS
from ._arm import DEFAULT_ELEMENTS as DEFAULT_ELEMENTS
from ._arm import Arm as Arm
from ._arm_report import arm_bending as arm_bending
from ._chain_contacts import ChainContacts as ChainContacts
from ._chain_contacts import ContactOptions as ContactOptions
from ._chain_contacts import ContactSummary as ContactSummary
from ._chain_contacts import ContactTurn as ContactTurn
from ._chain_contacts import contacts_note as contacts_note
from ._chain_contacts import seat_landings as seat_landings
from ._compensate import Compensation as Compensation
from ._compensate import check_smooth as check_smooth
from ._compensate import compensate as compensate
from ._compensate import compensated_lift as compensated_lift
from ._compensate import deviation_from_law as deviation_from_law
from ._contact import ContactGeometry as ContactGeometry
from ._contact import Geometry as Geometry
from ._contact import JoinCurvature as JoinCurvature
from ._contact import NodeContact as NodeContact
from ._contact import RefinedStress as RefinedStress
from ._contact import cam_geometry as cam_geometry
from ._contact import contact_geometry as contact_geometry
from ._contact import node_contact as node_contact
from ._contact import refined_contact_stress as refined_contact_stress
from ._cycle import Cycle as Cycle
from ._cycle import TrainPeaks as TrainPeaks
from ._design import design_segment as design_segment
from ._design import write_program as write_program
from ._drive import DRIVE_TABLE_FILE_NAMES as DRIVE_TABLE_FILE_NAMES
from ._drive import DRIVE_TABLE_FORMATS as DRIVE_TABLE_FORMATS
from ._drive import DriveTable as DriveTable
from ._drive import check_drive_table_arguments as check_drive_table_arguments
from ._drive import drive_table as drive_table
from ._drive import read_drive_table as read_drive_table
from ._drive import write_drive_table as write_drive_table
from ._dxf_import import DxfProfile as DxfProfile
from ._dxf_import import lift_from_dxf as lift_from_dxf
from ._dxf_import import read_dxf_profile as read_dxf_profile
from ._dynamics import SpeedSummary as SpeedSummary
from ._dynamics import SteadyState as SteadyState
from ._dynamics import block_memory_bytes as block_memory_bytes
from ._dynamics import node_contact_force as node_contact_force
from ._dynamics import startup as startup
from ._export import MAX_PROFILE_POINTS as MAX_PROFILE_POINTS
from ._export import Profile as Profile
from ._export import profile as profile
from ._export import shape as shape
from ._export import write_csv as write_csv
from ._export import write_dxf as write_dxf
from ._follower import FOLLOWER_KINDS as FOLLOWER_KINDS
from ._follower import MAX_PRESSURE_ANGLE_DEG as MAX_PRESSURE_ANGLE_DEG
from ._follower import Follower as Follower
from ._follower import Materials as Materials
from ._follower import follower_kinds as follower_kinds
from ._groove import MAX_GROOVE_SAMPLES as MAX_GROOVE_SAMPLES
from ._groove import MAX_TURNS as MAX_TURNS
from ._groove import SETTLED_DEG as SETTLED_DEG
from ._groove import SETTLED_REL as SETTLED_REL
from ._groove import GrooveTurn as GrooveTurn
from ._groove import Impact as Impact
from ._groove import TurnLaw as TurnLaw
from ._groove import groove_turns as groove_turns
from ._jump import ContactForceBound as ContactForceBound
from ._jump import Flight as Flight
from ._jump import flight as flight
from ._jump import flights as flights
from ._jump import flights_at as flights_at
from ._jump import jump_speed_rpm as jump_speed_rpm
from ._jump import min_preload_n as min_preload_n
from ._jump import scan_speeds as scan_speeds
from ._machine import Machine as Machine
from ._machine import MachineReport as MachineReport
from ._machine import ShaftSpeedReport as ShaftSpeedReport
from ._machine import analyse_machine as analyse_machine
from ._machine import is_machine_file as is_machine_file
from ._machine import shaft_torque as shaft_torque
from ._motion import EndState as EndState
from ._motion import Join as Join
from ._motion import segment_kinematics as segment_kinematics
from ._motor import INERTIA_RATIO_LIMIT as INERTIA_RATIO_LIMIT
from ._motor import RMS_SHARE_LIMIT as RMS_SHARE_LIMIT
from ._motor import Check as Check
from ._motor import Drive as Drive
from ._motor import DutyCycle as DutyCycle
from ._motor import Motor as Motor
from ._motor import MotorChoice as MotorChoice
from ._motor import MotorLoad as MotorLoad
from ._motor import MotorSizing as MotorSizing
from ._motor import choose_motor as choose_motor
from ._motor import duty_cycle as duty_cycle
from ._motor import read_motors as read_motors
from ._motor import size_motor as size_motor
from ._objective_rules import design_objectives as design_objectives
from ._objective_rules import design_refusal as design_refusal
from ._oscillator import Oscillator as Oscillator
from ._outputs import BUILT_IN_OUTPUTS as BUILT_IN_OUTPUTS
from ._outputs import Outputs as Outputs
from ._outputs import Probe as Probe
from ._outputs import ProbeContext as ProbeContext
from ._outputs import probe as probe
from ._program import Program as Program
from ._program import segment_band as segment_band
from ._program import with_law as with_law
from ._reader import example_names as example_names
from ._reader import example_path as example_path
from ._reader import program_path as program_path
from ._report import Report as Report
from ._report import SpeedReport as SpeedReport
from ._report import analyse as analyse
from ._report import kinematic_acceleration_m_s2 as kinematic_acceleration_m_s2
from ._report import max_contact_stress as max_contact_stress
from ._report import period_ratios as period_ratios
from ._report import response as response
from ._report import steady_state as steady_state
from ._segment import MAX_SEGMENTS as MAX_SEGMENTS
from ._segment import Segment as Segment
from ._servo import program_motor_choice as program_motor_choice
from ._speeds import IMPLAUSIBLE_PERIOD_RATIO as IMPLAUSIBLE_PERIOD_RATIO
from ._speeds import IMPLAUSIBLE_RPM as IMPLAUSIBLE_RPM
from ._speeds import Speeds as Speeds
from ._speeds import warn_implausible as warn_implausible
from ._torque import DEFAULT_SPEED_FLUCTUATION as DEFAULT_SPEED_FLUCTUATION
from ._train import CLASSIC_FIELDS as CLASSIC_FIELDS
from ._train import Body as Body
from ._train import Chain as Chain
from ._train import Seat as Seat
from ._train import Spring as Spring
from ._train import chain_from_dict as chain_from_dict
from ._train import load_chain as load_chain
from ._turn import JOIN_TOLERANCE_DEG as JOIN_TOLERANCE_DEG
from ._turn import Turn as Turn
from ._warnings import ABSURD_SIZES as ABSURD_SIZES
from ._warnings import LIFT_ERROR_RATIO as LIFT_ERROR_RATIO
from ._warnings import MAX_HALF_WIDTH_RATIO as MAX_HALF_WIDTH_RATIO
from ._warnings import MAX_SEAT_COMPRESSION_MM as MAX_SEAT_COMPRESSION_MM
from ._warnings import MODULUS_RANGE_GPA as MODULUS_RANGE_GPA
from ._warnings import design_warnings as design_warnings
from ._writers import RESPONSE_SPEEDS as RESPONSE_SPEEDS
from ._writers import write_machine_report as write_machine_report
from ._writers import write_report as write_report

if TYPE_CHECKING:  # the lazy names, for type checkers and the API reference
    from ._figures import motor_figure as motor_figure
    from ._figures import save_figures as save_figures
    from ._figures import shaft_figures as shaft_figures
    from ._objectives import AbstractProgramObjective as AbstractProgramObjective
    from ._objectives import MaxPreload as MaxPreload
    from ._objectives import MaxProgramResidual as MaxProgramResidual
    from ._seating import MaxSeatingVelocity as MaxSeatingVelocity
    from ._seating import seating_design as seating_design

# Loaded on first use: MaxPreload subclasses camjax.law_design's objective (which imports
# optax) and the figures import matplotlib.
_LAZY = {"AbstractProgramObjective": "._objectives", "MaxPreload": "._objectives", "MaxProgramResidual": "._objectives",
         "MaxSeatingVelocity": "._seating", "seating_design": "._seating", "save_figures": "._figures", "shaft_figures": "._figures",
         "motor_figure": "._figures"}


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value

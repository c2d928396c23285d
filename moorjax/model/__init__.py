"""The physical model: axial laws, line types, environment, ends, lines, scenes."""

from .axial import AbstractAxialLaw as AbstractAxialLaw
from .axial import Bilateral as Bilateral
from .axial import LinearEA as LinearEA
from .axial import PolyesterMBL as PolyesterMBL
from .axial import PolyesterWu as PolyesterWu
from .axial import TabulatedEA as TabulatedEA
from .ends import AbstractClampedEnd as AbstractClampedEnd
from .ends import AbstractEnd as AbstractEnd
from .ends import BodyEnd as BodyEnd
from .ends import ClampedEnd as ClampedEnd
from .ends import FixedEnd as FixedEnd
from .ends import KinematicEnd as KinematicEnd
from .ends import MovingClampedEnd as MovingClampedEnd
from .ends import SinePath as SinePath
from .ends import TabulatedPath as TabulatedPath
from .environment import AbstractCurrent as AbstractCurrent
from .environment import AbstractDepthCurrent as AbstractDepthCurrent
from .environment import Bathymetry as Bathymetry
from .environment import Environment as Environment
from .environment import GridCurrent as GridCurrent
from .environment import ProfileCurrent as ProfileCurrent
from .environment import TimeProfileCurrent as TimeProfileCurrent
from .environment import Seabed as Seabed
from .environment import SeabedFriction as SeabedFriction
from .environment import UniformCurrent as UniformCurrent
from .line import Line as Line
from .line import LineState as LineState
from .line_type import AddedMass as AddedMass
from .line_type import LineType as LineType
from .line_type import MorisonDrag as MorisonDrag
from .scene import Scene as Scene
from .waves import AbstractWaveKinematics as AbstractWaveKinematics
from .waves import AiryWaves as AiryWaves
from .waves import ExternalWaves as ExternalWaves
from .waves import GridAiryWaves as GridAiryWaves
from .waves import IrregularWave as IrregularWave
from .waves import wave_number as wave_number

__all__ = [
    'AbstractAxialLaw',
    'AbstractClampedEnd',
    'AbstractCurrent',
    'AbstractDepthCurrent',
    'AbstractEnd',
    'AbstractWaveKinematics',
    'AddedMass',
    'AiryWaves',
    'Bilateral',
    'Environment',
    'ExternalWaves',
    'Bathymetry',
    'BodyEnd',
    'ClampedEnd',
    'FixedEnd',
    'GridAiryWaves',
    'IrregularWave',
    'KinematicEnd',
    'Line',
    'LineState',
    'LineType',
    'LinearEA',
    'MorisonDrag',
    'MovingClampedEnd',
    'PolyesterMBL',
    'PolyesterWu',
    'GridCurrent',
    'ProfileCurrent',
    'TimeProfileCurrent',
    'Scene',
    'Seabed',
    'SeabedFriction',
    'SinePath',
    'TabulatedEA',
    'TabulatedPath',
    'UniformCurrent',
    'wave_number',
]

"""The mapping advisor: from a profile of a project to the mapping that meets a chain's deadline.

``profile`` (run the project, or read a profile file) → ``calibrate`` (this machine's transport
costs, measured with hetros's own ping-pongs, cached) → ``model`` (a candidate mapping simulated: chain
latencies, core loads) → ``search`` (every candidate, or HiGHS's proposals beyond a few thousand)
→ ``report`` (a table, the chosen mapping as a project file, a timeline) → ``verify`` (launch and
measure). It sits on top: it plans projects, launches them and looks inside, like the CLI.
"""

from ._advise import Advice, Options, advise, mapping_of, profile_project, refuse_busy, verify, write
from ._calibrate import Calibration, calibration
from ._chains import Chain, ChainLatency, Published, measure
from ._measure import BUSY_LIMIT, busy_share, copy_times, ping_pong_plan
from ._model import Mapping, Placement, Prediction, predict
from ._profile import Handling, NodeProfile, Profile, TopicProfile
from ._report import write_project
from ._search import Candidate, Limits, search

__all__ = [
    "BUSY_LIMIT",
    "Advice",
    "Calibration",
    "Candidate",
    "Chain",
    "ChainLatency",
    "Handling",
    "Limits",
    "Mapping",
    "NodeProfile",
    "Options",
    "Placement",
    "Prediction",
    "Profile",
    "Published",
    "TopicProfile",
    "advise",
    "busy_share",
    "calibration",
    "copy_times",
    "mapping_of",
    "measure",
    "ping_pong_plan",
    "predict",
    "profile_project",
    "refuse_busy",
    "search",
    "verify",
    "write",
    "write_project",
]

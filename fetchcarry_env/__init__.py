"""fetchcarry_env: the fetch-and-carry world with push-aside, simulated in PyBullet.

Importing this package registers the Gymnasium ids (``FetchCarryPush-v0``, and
``FetchCarryPushPhases-v0``: the same env with ``Discrete(K)`` candidate phases and exact masks). The
scenario model and the geometry import no simulator, so the planner can use them
where PyBullet is not installed.
"""

from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Heading, Rect
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.phases import PhaseLayout
from fetchcarry_env.registration import register_envs
from fetchcarry_env.scenario import Scenario, ScenarioError

register_envs()

__all__ = [
    "HEADINGS",
    "Action",
    "Capacity",
    "Heading",
    "Lattice",
    "Mode",
    "PhaseLayout",
    "Rect",
    "Scenario",
    "ScenarioError",
    "WorldState",
]

# my_policies.py: the first allowed candidate phase, every step
import numpy as np


class FirstAllowed:
    def predict(self, observation, state=None, episode_start=None, deterministic=False, action_masks=None):
        return int(np.flatnonzero(action_masks)[0]), state


def make_policy(env):
    return FirstAllowed()

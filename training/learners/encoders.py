"""Networks that score every candidate phase from the flat observation vector.

``mlp``
    The observation vector, standardised with the demonstrations' mean and spread,
    through two hidden layers to one score per candidate. With ``relative`` (the
    default), :class:`RelativeFeatures` appends positions relative to the base and
    each piece of clutter relative to each goal, which the flat vector only holds in
    absolute coordinates.
``set``
    Object-centric: one token per slot of the observation (a robot token holding the
    area and the base, then each posture, object, piece of clutter, table and
    obstacle; :func:`fetchcarry_env.observation.observation_layout` names the slices),
    each kind projected by its own layer, mixed by a small Transformer in which absent
    slots (presence flag 0) are masked out (with ``relative``, each token also holds its
    x, y columns minus the base's). Each token scores its own candidates: an
    object token its pick and place poses, a clutter token its pushes and approach
    poses, a table or obstacle token its waypoints; so the weights do not depend on
    how many slots there are, and a network built for a larger capacity loads them.
``cnn``
    Pixels (``obs_mode`` ``topdown`` or ``rgbd``; :mod:`fetchcarry_env.observations`):
    the images, flattened into the network's input row by :func:`network_input` (uint8
    values, the two RGB-D cameras stacked as 8 channels), scaled to [0, 1], with two
    coordinate channels appended (CoordConv), through stride-2 convolutions down to at
    most 16 x 16 cells and one 3 x 3 convolution, then two layers to the scores
    (:class:`ImageScorer`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from fetchcarry_env.geometry import HEADINGS, heading_vector
from fetchcarry_env.observation import FIELDS, Capacity, observation_layout
from fetchcarry_env.observations import get_mode
from fetchcarry_env.phases import PhaseLayout

COORD_SCALE = 5.0  # metres: coordinates are divided by this in the set encoder (the families' floor is 7 m)
SET_HEADS = 4  # attention heads of the set encoder
SET_LAYERS = 2  # Transformer layers of the set encoder
RELATIVE_COLUMNS: dict[str, tuple[int, ...]] = {
    "posture": (),
    "object": (1, 2, 4, 5),  # x, y, goal_x, goal_y
    "clutter": (1, 2, 3, 4),  # min_x, min_y, max_x, max_y
    "table": (1, 2, 3, 4),
    "obstacle": (1, 2, 3, 4),
}
"""Columns of each slot (:data:`FIELDS`) that are x, y pairs: the set encoder's relative features subtract the base."""


CNN_WIDTHS = (32, 64, 64)  # channels of the cnn's stride-2 convolutions (the last also of its 3 x 3 one)
CNN_CELLS = 16  # the stride-2 convolutions go on until the feature map is at most this many cells a side


def network_input(observation: dict[str, np.ndarray], obs_mode: str) -> np.ndarray:
    """What a network of ``obs_mode`` reads: the state vector, or the images flattened (one row per observation).

    ``observation`` is one observation (arrays as the env gives them) or a batch (a leading
    axis on every array). ``state``: ``observation["observation"]`` as float32; ``topdown``:
    the map, ``(7 * S * S,)`` uint8; ``rgbd``: the head and overhead images stacked as
    8 channels, ``(8 * C * C,)`` uint8. ``KeyError`` names the key a missing image needs.
    """
    if obs_mode == "state":
        return np.asarray(observation["observation"], dtype=np.float32)
    keys = get_mode(obs_mode).keys
    missing = [key for key in keys if key not in observation]
    if missing:
        raise KeyError(f"this network sees obs_mode {obs_mode!r}: the observation lacks {', '.join(missing)}")
    images = [np.asarray(observation[key], dtype=np.uint8) for key in keys]
    batched = images[0].ndim == 4
    image = np.concatenate(images, axis=1 if batched else 0)
    return image.reshape(len(image), -1) if batched else image.reshape(-1)


def input_size(space: Any, obs_mode: str) -> int:
    """The length of :func:`network_input`'s row for an env's ``Dict`` observation ``space`` in ``obs_mode``."""
    if obs_mode == "state":
        return int(space["observation"].shape[0])
    return sum(int(np.prod(space[key].shape)) for key in get_mode(obs_mode).keys)


def image_shape(obs_mode: str, features: int) -> tuple[int, int, int]:
    """``(channels, side, side)`` of the images of ``obs_mode`` whose flattened row has ``features`` values.

    ``ValueError`` unless they make square images of 8 to 1024 pixels a side.
    """
    mode = get_mode(obs_mode)
    if not mode.keys:
        raise ValueError(f"the cnn encoder reads the images of an obs_mode, and {obs_mode!r} has none")
    return mode.input_channels, mode.side(features), mode.side(features)


def build_network(config: Any, capacity: Capacity, candidates: int, observations: torch.Tensor) -> nn.Module:
    """The network ``config.encoder`` names, for ``candidates`` scores; ``observations`` set the MLP's scaling."""
    if config.encoder == "cnn":
        return ImageScorer(image_shape(config.obs_mode, observations.shape[1]), candidates, config.hidden)
    if config.encoder == "mlp":
        features = RelativeFeatures(capacity) if getattr(config, "relative", False) else None
        network = FlatMLP(observations, candidates, config.hidden, features)
        if getattr(config, "push_scores", False):
            layout = PhaseLayout.for_postures(capacity=capacity)
            if layout.size != candidates:
                raise ValueError(f"push scores need the default candidate layout ({layout.size}), got {candidates}")
            network.push = PushScores(capacity, layout)
        return network
    layout = PhaseLayout.for_postures(capacity=capacity)
    if layout.size != candidates:
        raise ValueError(f"the set encoder needs the default candidate layout ({layout.size}), got {candidates}")
    return SetScorer(capacity, layout, width=min(config.hidden, 128), relative=getattr(config, "relative", False))


class ImageScorer(nn.Module):
    """Images (a flattened uint8 row, :func:`network_input`) -> a small CNN -> two layers -> one score per candidate.

    The pixels are scaled to [0, 1] and two channels of x and y (from -1 to 1) are
    appended, so that the convolutions know where a thing is (the candidates are
    numbered by the things' slots and poses, and an object's slot is its pixel value).
    """

    def __init__(self, shape: tuple[int, int, int], candidates: int, hidden: int) -> None:
        super().__init__()
        self.shape = shape
        channels, side, _ = shape
        y, x = torch.meshgrid(torch.linspace(-1, 1, side), torch.linspace(-1, 1, side), indexing="ij")
        self.register_buffer("coordinates", torch.stack([x, y])[None])
        layers: list[nn.Module] = []
        width, cells, k = channels + 2, side, 0
        while cells > CNN_CELLS or k == 0:
            out = CNN_WIDTHS[min(k, len(CNN_WIDTHS) - 1)]
            layers += [nn.Conv2d(width, out, kernel_size=4, stride=2), nn.ReLU()]
            width, cells, k = out, (cells - 4) // 2 + 1, k + 1
        layers += [nn.Conv2d(width, CNN_WIDTHS[-1], kernel_size=3), nn.ReLU(), nn.Flatten()]
        cells -= 2
        self.convolutions = nn.Sequential(*layers)
        self.head = nn.Sequential(
            nn.Linear(CNN_WIDTHS[-1] * cells * cells, hidden),
            nn.ReLU(),
            nn.Linear(hidden, candidates),
        )

    def features(self, flat: torch.Tensor) -> torch.Tensor:
        images = flat.reshape(len(flat), *self.shape).float() / 255.0
        coordinates = self.coordinates.expand(len(flat), -1, -1, -1)
        return self.head[:-1](self.convolutions(torch.cat([images, coordinates], dim=1)))

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        return self.head[-1](self.features(flat))

    def candidate_scores(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        """``forward(flat)[:, candidates]``, computing only those rows of the last layer."""
        last = self.head[-1]
        return F.linear(
            self.features(flat), last.weight.index_select(0, candidates), last.bias.index_select(0, candidates)
        )


class RelativeFeatures(nn.Module):
    """The flat observation vector followed by what a flat MLP finds hard to compute: differences of positions.

    Appended, each multiplied by its slots' presence flags (metres): every object's
    position and goal relative to the base and its goal relative to itself; every
    piece of clutter's, table's and obstacle's rectangle relative to the base; and every
    piece of clutter's centre relative to every object's goal (whether it covers it).
    No weights: a function of the vector alone.
    """

    def __init__(self, capacity: Capacity) -> None:
        super().__init__()
        self.capacity = capacity
        self.slices = observation_layout(capacity)
        self.size = self.extra_width(capacity)

    @staticmethod
    def extra_width(capacity: Capacity) -> int:
        """How many features are appended for ``capacity``."""
        rects = capacity.clutter + capacity.tables + capacity.obstacles
        return 6 * capacity.objects + 4 * rects + 2 * capacity.clutter * capacity.objects

    def _rows(self, flat: torch.Tensor, group: str, kind: str) -> torch.Tensor:
        return flat[:, self.slices[group]].reshape(len(flat), getattr(self.capacity, group), len(FIELDS[kind]))

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        robot = flat[:, self.slices["robot"]]
        base = robot[:, None, :2]  # (B, 1, 2): x, y
        objects = self._rows(flat, "objects", "object")
        there = objects[..., :1]  # presence flags
        position, goal = objects[..., 1:3], objects[..., 4:6]
        parts = [torch.cat([position - base, goal - base, goal - position], dim=-1) * there]
        centres = []
        for group, kind in (("clutter", "clutter"), ("tables", "table"), ("obstacles", "obstacle")):
            rows = self._rows(flat, group, kind)
            corners = rows[..., 1:5] - base.repeat(1, 1, 2)
            parts.append(corners * rows[..., :1])
            if group == "clutter":
                centres.append(((rows[..., 1:3] + rows[..., 3:5]) / 2, rows[..., :1]))
        centre, present = centres[0]
        between = (centre[:, :, None, :] - goal[:, None, :, :]) * present[:, :, None, :] * there[:, None, :, :]
        parts.append(between)
        extra = torch.cat([part.reshape(len(flat), -1) for part in parts], dim=1)
        return torch.cat([flat, extra], dim=1)


class FlatMLP(nn.Module):
    """Standardised observation vector (with :class:`RelativeFeatures` if given) -> two ReLU layers -> scores."""

    def __init__(
        self, observations: torch.Tensor, candidates: int, hidden: int, features: nn.Module | None = None
    ) -> None:
        super().__init__()
        self.features = features if features is not None else nn.Identity()
        with torch.no_grad():
            observations = self.features(observations)
        mean = observations.mean(dim=0) if len(observations) > 1 else torch.zeros(observations.shape[1])
        spread = observations.std(dim=0) if len(observations) > 1 else torch.ones(observations.shape[1])
        self.register_buffer("mean", mean)
        self.register_buffer("spread", torch.clamp(spread, min=1e-3))
        self.layers = nn.Sequential(
            nn.Linear(observations.shape[1], hidden),
            nn.ReLU(),
            nn.Linear(hidden, hidden),
            nn.ReLU(),
            nn.Linear(hidden, candidates),
        )

        self.push: nn.Module | None = None  # a PushScores added to the scores, if set

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        scores = self.layers((self.features(flat) - self.mean) / self.spread)
        return scores if self.push is None else scores + self.push(flat)

    def candidate_scores(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        """``forward(flat)[:, candidates]``, computing only those columns.

        The last layer is most of the weights (one row of ``hidden`` per candidate, 4 MB
        for 4,080 candidates and 256 units); a decision needs the rows of the allowed
        candidates only (some 30 of them), and fetching the rest from memory was most of
        its time.
        """
        hidden = self.layers[:-1]((self.features(flat) - self.mean) / self.spread)
        last = self.layers[-1]
        scores = F.linear(hidden, last.weight.index_select(0, candidates), last.bias.index_select(0, candidates))
        return scores if self.push is None else scores + self.push(flat).index_select(1, candidates)


class PushScores(nn.Module):
    """Scores from what each push would do: does the piece of clutter still cover a goal afterwards?

    For the push candidate of clutter ``c`` along ``d`` by ``s`` cells, the piece's
    rectangle shifted ``s`` cells along ``d`` (the stroke moves it as far as the base)
    is compared with every goal not yet delivered: the margin is the least distance
    from the shifted rectangle to a goal's centre minus that object's radius (metres;
    positive: no goal covered, as the env's place check asks). Its features (margin
    after, margin before, whether it clears, the stroke) go through a small MLP to a
    score added to that candidate's. Each approach candidate of ``c`` along ``d``
    gets one from the best push along ``d`` (its margin, whether one clears, the
    shortest stroke that does). The heading and the pose offsets get nothing here: the
    flat network scores those. Zero for empty slots.
    """

    def __init__(self, capacity: Capacity, layout: PhaseLayout, resolution: float = 0.05, hidden: int = 16) -> None:
        super().__init__()
        self.capacity, self.layout = capacity, layout
        self.slices = observation_layout(capacity)
        units = torch.tensor([heading_vector(h) for h in HEADINGS], dtype=torch.float32)  # (4, 2)
        strokes = torch.arange(1, layout.strokes + 1, dtype=torch.float32)
        self.register_buffer("shifts", units[:, None, :] * strokes[None, :, None] * resolution)  # (4, S, 2)
        self.push_head = nn.Sequential(nn.Linear(4, hidden), nn.ReLU(), nn.Linear(hidden, 1))
        self.approach_head = nn.Sequential(nn.Linear(3, hidden), nn.ReLU(), nn.Linear(hidden, 1))

    def margins(self, flat: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``(after, before, present)``: margins (B, C, 4, S) after each push, (B, C) before; clutter flags (B, C)."""
        batch, cap = len(flat), self.capacity
        clutter = flat[:, self.slices["clutter"]].reshape(batch, cap.clutter, len(FIELDS["clutter"]))
        objects = flat[:, self.slices["objects"]].reshape(batch, cap.objects, len(FIELDS["object"]))
        present = clutter[..., 0] > 0.5
        waiting = (objects[..., 0] > 0.5) & (objects[..., 10] < 0.5)  # present, not delivered
        goal, radius = objects[..., 4:6], objects[..., 7]

        def margin(low: torch.Tensor, high: torch.Tensor) -> torch.Tensor:
            # low, high: (..., 2) rectangle corners; least over goals of distance to the centre minus the radius
            point = goal.reshape(batch, *([1] * (low.dim() - 2)), cap.objects, 2)
            gap = torch.clamp(torch.maximum(low[..., None, :] - point, point - high[..., None, :]), min=0.0)
            value = gap.norm(dim=-1) - radius.reshape(point.shape[:-1])
            value = value.masked_fill(~waiting.reshape(point.shape[:-1]), 1.0)
            return value.min(dim=-1).values.clamp(max=1.0)

        low, high = clutter[..., 1:3], clutter[..., 3:5]  # (B, C, 2)
        before = margin(low, high)  # (B, C)
        shifted_low = low[:, :, None, None, :] + self.shifts  # (B, C, 4, S, 2)
        shifted_high = high[:, :, None, None, :] + self.shifts
        after = margin(shifted_low, shifted_high)
        return after, before, present

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        batch, layout = len(flat), self.layout
        after, before, present = self.margins(flat)
        strokes = layout.strokes
        stroke = (torch.arange(1, strokes + 1, dtype=flat.dtype) / strokes).expand_as(after)
        clears = (after > 0).to(flat.dtype)
        push_features = torch.stack([after, before[:, :, None, None].expand_as(after), clears, stroke], dim=-1)
        push = self.push_head(push_features)[..., 0] * present[:, :, None, None]  # (B, C, 4, S)
        first = torch.where(clears > 0, stroke, torch.full_like(stroke, 2.0)).min(dim=-1).values  # (B, C, 4)
        approach_features = torch.stack([after.max(dim=-1).values, clears.max(dim=-1).values, first], dim=-1)
        approach = self.approach_head(approach_features)[..., 0] * present[:, :, None]  # (B, C, 4)
        scores = flat.new_zeros(batch, layout.size)
        push_shape, approach_shape = layout.shape("push"), layout.shape("approach")  # (C, 4, 3, S), (C, 4, 3, F, L)
        scores[:, layout.kind_slice("push")] = push[:, :, :, None, :].expand(batch, *push_shape).reshape(batch, -1)
        per_pose = approach[:, :, :, None, None, None].expand(batch, *approach_shape)
        scores[:, layout.kind_slice("approach")] = per_pose.reshape(batch, -1)
        return scores


class SetScorer(nn.Module):
    """Tokens per slot, a masked Transformer, and per-token heads scoring each token's candidates."""

    def __init__(self, capacity: Capacity, layout: PhaseLayout, width: int = 64, relative: bool = False) -> None:
        super().__init__()
        self.capacity, self.layout, self.relative = capacity, layout, relative
        self.slices = observation_layout(capacity)
        self.robot_width = len(FIELDS["area"]) + len(FIELDS["robot"])
        self.embed = nn.ModuleDict(
            {
                kind: nn.Linear(len(FIELDS[kind]) + (len(RELATIVE_COLUMNS[kind]) if relative else 0), width)
                for kind in ("posture", "object", "clutter", "table", "obstacle")
            }
        )
        self.embed["robot"] = nn.Linear(self.robot_width, width)
        block = nn.TransformerEncoderLayer(width, SET_HEADS, 2 * width, dropout=0.0, batch_first=True)
        self.mixer = nn.TransformerEncoder(block, SET_LAYERS, enable_nested_tensor=False)
        per_object = int(np.prod(layout.shape("pick")[1:]))
        per_clutter = (int(np.prod(layout.shape("push")[1:])), int(np.prod(layout.shape("approach")[1:])))
        per_blocker = (int(np.prod(layout.shape("waypoint")[1:])), int(np.prod(layout.shape("edge")[1:])))
        self.splits = {"object": (per_object, per_object), "clutter": per_clutter, "blocker": per_blocker}
        self.heads = nn.ModuleDict(
            {kind: nn.Linear(2 * width, sum(self.splits[kind])) for kind in ("object", "clutter", "blocker")}
        )
        # Index tensors and slot bounds, built once (a decision is a few hundred microseconds of small ops).
        self.groups = (("postures", "posture"), ("objects", "object"), ("clutter", "clutter"))
        self.groups += (("tables", "table"), ("obstacles", "obstacle"))
        self.bounds = [int(b) for b in np.cumsum([1, *(getattr(capacity, g) for g, _ in self.groups)])]
        self.columns = {kind: torch.tensor(columns) for kind, columns in RELATIVE_COLUMNS.items() if columns}
        self.axes = {kind: torch.arange(len(columns)) % 2 for kind, columns in self.columns.items()}  # x, y, x, y

    def _tokens(self, flat: torch.Tensor, group: str, kind: str) -> tuple[torch.Tensor, torch.Tensor]:
        """``(tokens, present)`` of one group of slots: embedded features and presence flags.

        With ``relative``, each token also holds its x and y columns minus the base's
        (:data:`RELATIVE_COLUMNS`), zero in absent slots.
        """
        count = getattr(self.capacity, group)
        rows = flat[:, self.slices[group]].reshape(len(flat), count, len(FIELDS[kind]))
        parts = [rows[..., :1], rows[..., 1:] / COORD_SCALE]
        if self.relative and kind in self.columns:
            base = flat[:, self.slices["robot"]][:, None, :2]
            offsets = base[..., self.axes[kind]]
            parts.append((rows[..., self.columns[kind]] - offsets) * rows[..., :1] / COORD_SCALE)
        return self.embed[kind](torch.cat(parts, dim=-1)), rows[..., 0] > 0.5

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        tokens, present = self._all_tokens(flat)
        return self._heads(self.mixer(tokens, src_key_padding_mask=~present))

    def candidate_scores(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        """``forward(flat)[:, candidates]`` for one row, mixing only the slots that are present.

        Absent slots are masked out of attention in :meth:`forward`, so leaving them out
        of the Transformer changes no present token; it mixes some 10-15 tokens instead
        of every slot of the capacity (35). An absent slot's token is then zero before
        its head, so its candidates' scores differ from :meth:`forward`'s, but a mask
        never allows them.
        """
        if len(flat) != 1:
            raise ValueError(f"candidate_scores takes one observation (a row), got {len(flat)}")
        tokens, present = self._all_tokens(flat)
        kept = present[0].nonzero()[:, 0]
        mixed = torch.zeros_like(tokens).index_copy(1, kept, self.mixer(tokens.index_select(1, kept)))
        return self._heads(mixed).index_select(1, candidates)

    def _all_tokens(self, flat: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """``(tokens, present)``: the robot token then every slot's, (batch, slots, width), and their flags."""
        robot = self.embed["robot"](flat[:, : self.robot_width] / COORD_SCALE)[:, None, :]
        tokens, present = [robot], [torch.ones(len(flat), 1, dtype=torch.bool)]
        for group, kind in self.groups:
            t, p = self._tokens(flat, group, kind)
            tokens.append(t)
            present.append(p)
        return torch.cat(tokens, dim=1), torch.cat(present, dim=1)

    def _heads(self, mixed: torch.Tensor) -> torch.Tensor:
        """Every candidate's score from the mixed tokens, in the phase layout's order."""
        batch = len(mixed)
        context = mixed[:, :1, :]  # the robot token, after mixing: what every head also sees
        bounds = self.bounds
        objects = mixed[:, bounds[1] : bounds[2]]
        clutter = mixed[:, bounds[2] : bounds[3]]
        blockers = mixed[:, bounds[3] : bounds[5]]
        scores = {}
        for name, tokens_of in (("object", objects), ("clutter", clutter), ("blocker", blockers)):
            joined = torch.cat([tokens_of, context.expand(-1, tokens_of.shape[1], -1)], dim=-1)
            first, second = self.heads[name](joined).split(self.splits[name], dim=-1)
            scores[name] = (first.reshape(batch, -1), second.reshape(batch, -1))
        # The layout's order: pick, place, push, approach, waypoint, edge.
        return torch.cat([*scores["object"], *scores["clutter"], *scores["blocker"]], dim=1)


class Ensemble(nn.Module):
    """Several networks scoring the same candidates, as one: the mean of their log-probabilities.

    The mean of the members' log-softmax scores is the log of the product of their
    distributions over the candidates (up to a constant), which the policy renormalises
    over the allowed ones: a candidate ranks first when the members agree on it, and one
    that any member finds very unlikely is pulled down.
    """

    def __init__(self, members: list[nn.Module]) -> None:
        super().__init__()
        if len(members) < 2:
            raise ValueError(f"an ensemble needs at least two networks, got {len(members)}")
        self.members = nn.ModuleList(members)

    def forward(self, flat: torch.Tensor) -> torch.Tensor:
        return torch.stack([torch.log_softmax(member(flat), dim=1) for member in self.members]).mean(dim=0)

    def candidate_scores(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        """The mean of the members' scores of ``candidates`` only, without their log-softmax.

        It differs from ``forward(flat)[:, candidates]`` by a constant per row (the mean of
        the members' log normalisers), which changes neither the candidates' order nor a
        softmax over them, and it needs no member's full scores. It is also exact where
        ``forward`` rounds: subtracting a normaliser of 20-35 makes scores that differ by
        less than about 1e-6 equal, and then ``argmax`` takes the first. That happens among
        candidates no member was trained on (their weights have decayed to about zero),
        e.g. the third and fourth object of ``more-objects``: there the two choose
        differently (85 of 100 episodes of the published ensemble on that split), among
        candidates the ensemble cannot tell apart anyway.
        """
        return torch.stack([candidate_scores(member, flat, candidates) for member in self.members]).mean(dim=0)


def candidate_scores(network: nn.Module, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
    """``network``'s scores of ``candidates`` (indices): its own ``candidate_scores`` if it has one, else forward's."""
    if hasattr(network, "candidate_scores"):
        return network.candidate_scores(flat, candidates)
    return network(flat).index_select(1, candidates)


class CandidateScorer(nn.Module):
    """:func:`candidate_scores` of ``network`` as a module's ``forward(flat, candidates)``, to trace it."""

    def __init__(self, network: nn.Module) -> None:
        super().__init__()
        self.network = network

    def forward(self, flat: torch.Tensor, candidates: torch.Tensor) -> torch.Tensor:
        return candidate_scores(self.network, flat, candidates)

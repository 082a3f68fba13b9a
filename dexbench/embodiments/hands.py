"""The six dexterous hands: where their models come from and what their parts mean.

Everything here is data. Geometry-derived facts (the hand frame used for mounting, the
fingertip points) are computed from the models by `hand_frame.py`, so a hand is added by
writing one `HandSpec` and nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass, field

SIDES = ("right", "left")
# The Shadow hand model's contact softness, MuJoCo's default impedance: (solref: time
# constant s, damping ratio), (solimp)
SOFT_CONTACT = ((0.005, 1.0), (0.9, 0.95, 0.001, 0.5, 2.0))


@dataclass(frozen=True)
class HandSide:
    """One side (right or left) of a hand model: its file and its named parts."""

    entry: str
    palm_body: str
    fingertip_bodies: tuple[str, ...]  # thumb first, then index, middle, ...


@dataclass(frozen=True)
class RetargetSpec:
    """How human hand keypoints (21, MediaPipe/MANO order) drive this hand in teleoperation
    (`dexbench.teleop.retarget`).

    `tips`: the human keypoint each fingertip body (thumb first) follows. `scale`: robot
    over human hand size, here this hand's middle finger (knuckle joint to fingertip
    site, open model) over a human's 8.5 cm. The human wrist lands `scale` x 9.5 cm (a
    human's wrist-to-knuckle) behind the middle knuckle, and each fingertip goes where
    the human's offset from the wrist, times `scale`, puts it (in the hand frame H).
    """

    tips: tuple[int, ...] = (4, 8, 12, 16, 20)
    scale: float = 1.0


@dataclass(frozen=True)
class HandSpec:
    """A dexterous hand.

    Synergies map a regular expression over actuator names (without any prefix) to a
    joint target in radians; targets are clipped to the actuator's control range and
    actuators no pattern matches get the `open` target (or 0 clipped to range). The
    first matching pattern wins.
    """

    name: str
    collection: str
    sides: dict[str, HandSide]
    synergies: dict[str, dict[str, float]] = field(default_factory=dict)
    grasp_offset: tuple[float, float, float] = (0.1, 0.0, 0.05)
    """Where a 5 cm cube's centre should sit for the `power` synergy to hold it.

    Metres, in the hand frame (x along the fingers, z the palm normal, origin at the palm
    site). A top-down grasp puts the open hand's palm site at `cube - R_hand @ offset`,
    closes to `power` and lifts; `tests/test_embodiments.py` checks that this lifts a
    0.1 kg cube for every hand. Experts use it as the pre-grasp target.
    """
    bar_yaw: float = 0.0
    """How far (rad, about the palm normal) a bar handle held palm-down across the palm
    best turns from square to the fingers, for `power` to hold it against a heavy end's
    twist: the fingers' lengths and spread differ per hand, so the line they wrap firmest
    does too. Searched on GraspPan's handle (0.1 rad steps); 0: not searched."""
    shifts: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    """Added (m, hand frame) to the `shift` of a plan's grasp whose `hand_shift` names the
    key. The plans' shifts are the Shadow hand's; another hand's palm and fingers may
    put the same kind of grasp elsewhere on the object. `vessel`: a pour's side grasp
    round a vessel's body (a thicker palm or longer fingers start inside the vessel or
    hold it out of their hook); `rim`: a top grasp across a cup's rim; `tool`: a top grasp
    across a tool's handle next to its heavy head (the hammer); `handle`: a hook round a
    vessel's handle bar from outside (the kettle)."""
    vessel_turn: float = 0.0
    """Added (rad) to a pour's `grasp_turn` (about the palm normal) for a side grasp round a
    vessel's body: a hand whose fingers lie far apart reaches the rim with its middle
    finger while its lowest finger rests on the table, unless its fingers slant down."""
    hang_back: bool = False
    """Pinching a slender object off its middle to turn it end-down (`PinchPlan.hangs`):
    take the grasp whose longer part lies back towards the wrist, not out past the
    fingertips (False: whichever of the two is nearer the hand's yaw)."""
    soft_contacts: bool = False
    """Give the hand's geoms the Shadow hand's contact softness (`SOFT_CONTACT`) instead of
    its file's: LEAP's sets solref 1e-4 s and solimp 0.999, far stiffer than the 4 ms step
    resolves; a fingertip pressing a ball onto the table then kicked it off at 2-8 m/s
    (PushSmallSphereObstacleSlope: 4 of 20 episodes 'solved' that way, 18 launched)."""
    retarget: RetargetSpec = RetargetSpec()

    def shift_for(self, kind: str | None) -> tuple[float, float, float]:
        """This hand's correction (`shifts`) to grasps of `kind`; none for None."""
        return self.shifts.get(kind, (0.0, 0.0, 0.0)) if kind else (0.0, 0.0, 0.0)


def _shadow_side(p: str) -> HandSide:
    return HandSide(
        entry=f"{'right' if p == 'rh' else 'left'}_hand",
        palm_body=f"{p}_palm",
        fingertip_bodies=tuple(f"{p}_{f}distal" for f in ("th", "ff", "mf", "rf", "lf")),
    )


def _allegro_side(entry: str) -> HandSide:
    return HandSide(
        entry=entry,
        palm_body="palm",
        fingertip_bodies=("th_tip", "ff_tip", "mf_tip", "rf_tip"),
    )


def _leap_side(entry: str) -> HandSide:
    return HandSide(
        entry=entry,
        palm_body="palm",
        fingertip_bodies=("th_ds", "if_ds", "mf_ds", "rf_ds"),
    )


def _sharpa_side(side: str) -> HandSide:
    return HandSide(
        entry=f"{side}_hand",
        palm_body=f"{side}_hand_C_MC",
        fingertip_bodies=tuple(
            f"{side}_{f}_DP" for f in ("thumb", "index", "middle", "ring", "pinky")
        ),
    )


def _inspire_side(side: str) -> HandSide:
    s = side[0]
    return HandSide(
        entry=f"inspire_{side}_hand.xml",
        palm_body=f"{s}_palm",
        fingertip_bodies=tuple(
            f"{s}_{f}_distal" for f in ("thumb", "index", "middle", "ring", "pinky")
        ),
    )


def _wuji_side(side: str) -> HandSide:
    return HandSide(
        entry=f"mjcf/{side}.xml",
        palm_body=f"{side}_palm_link",
        fingertip_bodies=tuple(f"{side}_finger{i}_link4" for i in range(1, 6)),
    )


HANDS: dict[str, HandSpec] = {
    "shadow": HandSpec(
        name="shadow",
        retarget=RetargetSpec(scale=1.0),
        grasp_offset=(0.095, -0.013, 0.06),
        collection="shadow_hand",
        sides={"right": _shadow_side("rh"), "left": _shadow_side("lh")},
        synergies={
            "open": {},
            # Fingers hook over the cube's far face, the thumb (fully rotated) presses the
            # near face; tuned for the weak Menagerie finger actuators (kp 1, +-1 Nm).
            "power": {
                r"A_(FF|MF|RF|LF)J3$": 0.72,
                r"A_(FF|MF|RF|LF)J0$": 2.25,
                r"A_THJ5$": 1.05,
                r"A_THJ4$": 1.22,
                r"A_THJ2$": 0.14,
                r"A_THJ1$": 0.9,
            },
            "pinch": {
                r"A_FFJ3$": 0.9,
                r"A_FFJ0$": 1.0,
                r"A_(MF|RF|LF)J3$": 1.4,
                r"A_(MF|RF|LF)J0$": 2.4,
                r"A_THJ5$": 0.4,
                r"A_THJ4$": 1.2,
                r"A_THJ2$": 0.5,
                r"A_THJ1$": 0.5,
            },
            # Thumb and index tips meet under the palm, the other fingers stay straight
            # (clear of the table); the targets pass the meeting point, so the weak
            # fingers press on a thin object between the tips (`PinchPlan`). Every hand's
            # `tip_pinch` closes thumb and index only. Sharpa's (pen and knife) and
            # Inspire's (knife; its thumb flexion is sensitive: 0.25 and 0.35 lose the
            # knife) are tuned by trial, Wuji's searched (see there); the other hands' are
            # first guesses (their `pinch` without the other fingers).
            "tip_pinch": {
                r"A_FFJ3$": 1.5,
                r"A_FFJ0$": 0.9,
                r"A_THJ5$": 0.5,
                r"A_THJ4$": 1.22,
                r"A_THJ2$": 0.35,
                r"A_THJ1$": 0.3,
            },
        },
    ),
    "allegro": HandSpec(
        name="allegro",
        retarget=RetargetSpec(tips=(4, 8, 12, 16), scale=1.58),
        grasp_offset=(0.065, 0.016, 0.027),
        collection="wonik_allegro",
        sides={"right": _allegro_side("right_hand"), "left": _allegro_side("left_hand")},
        synergies={
            # The open thumb waits turned under the palm (resting on it), so that closing
            # it presses the cube's near face rather than sweeping into its side; the
            # fingers flex at every joint to hook the far face. Values (and the offset)
            # found by a local search scoring the PickCube expert's held lifts on the
            # floating, FR3, UR10e and xArm7 mounts together.
            "open": {
                r"tha0$": 0.648,
                r"tha1$": 0.43,
                r"tha2$": 1.747,
                r"tha3$": 1.481,
            },
            "power": {
                r"(ff|mf|rf)a1$": 0.931,
                r"(ff|mf|rf)a2$": 1.226,
                r"(ff|mf|rf)a3$": 1.207,
                r"tha0$": 1.608,
                r"tha1$": 1.499,
                r"tha2$": 0.881,
                r"tha3$": 0.966,
            },
            "pinch": {
                r"ffa1$": 1.0,
                r"ffa[23]$": 0.6,
                r"(mf|rf)a1$": 1.5,
                r"(mf|rf)a[23]$": 1.5,
                r"tha0$": 1.3,
                r"tha1$": 0.7,
                r"tha[23]$": 0.6,
            },
            "tip_pinch": {
                r"ffa1$": 1.0,
                r"ffa[23]$": 0.6,
                r"tha0$": 1.3,
                r"tha1$": 0.7,
                r"tha[23]$": 0.6,
            },
        },
    ),
    "leap": HandSpec(
        name="leap",
        retarget=RetargetSpec(tips=(4, 8, 12, 16), scale=1.38),
        grasp_offset=(0.02, -0.035, 0.069),
        soft_contacts=True,
        # Round a vessel: with the plans' shift (the Shadow hand's) the open fingers start
        # 2 cm inside it, and with the fingers level the middle one curls onto a 10 cm
        # cup's rim while the ring finger rests on the table. Held 1 cm further out along
        # the fingers, 1 cm lower in the hand, 3 cm further from the palm, the fingers
        # slanted 0.15 rad down: searched on GraspCup (30 random candidates on 4 envs,
        # then 14 near the best on 6 others); 10 episodes each, GraspCup 0.1 -> 0.5,
        # FunctionalPourCan 0 -> 0.5, FunctionalPourMug 0 -> 0.4 (GraspBleach stays 0).
        # Then 1 cm back along the fingers (x 0.01 -> 0): a grid over the shift's x, y, z
        # and the slant (floating, episodes 0-7) left only x mattering, with a narrow best
        # at 0 (x -0.01/-0.005/0/0.01: GraspCup 3/7/8/3 of 8, PourMug 5/4/7/1 of 8);
        # episodes 8-19: GraspCup 4 -> 12 of 12, PourMug 6 -> 7, PourCan 11 -> 12.
        # The hammer: at the Shadow hand's place the closing fingers knock the standing
        # hammer over; 2.5 cm towards the wrist and 1 cm further from the palm they close
        # round its handle. Grid search (x -0.03..0.015, y -0.01..0.01, z -0.01..0.02,
        # floating, episodes 0-5): y = 0, x -0.03..-0.015 solve 5-6 of 6, the Shadow's
        # place 3; checked on episodes 6-13: 8 of 8.
        shifts={"vessel": (0.0, 0.01, 0.03), "tool": (-0.025, 0.0, 0.01)},
        vessel_turn=-0.15,
        collection="leap_hand",
        sides={"right": _leap_side("right_hand"), "left": _leap_side("left_hand")},
        synergies={
            # Index and middle, bent mostly at the middle joint and turned on their
            # abduction joints, close on the cube's far face while the thumb presses its
            # near face (the ring finger curls alongside). The finger servos are slow, so
            # the targets overshoot the contact pose. Values (and the offset) found by a
            # local search over the PickCube expert on all four mounts (first attempts
            # weighted above retries), kept only where the floating hand's one-shot
            # scripted lift holds the cube.
            "open": {
                r"th_cmc_act$": 0.165,
                r"th_axl_act$": 0.08,
                r"th_mcp_act$": -0.137,
                r"th_ipl_act$": -0.794,
            },
            "power": {
                r"(if|mf)_mcp_act$": 0.404,
                r"(if|mf)_rot_act$": -0.421,
                r"(if|mf)_pip_act$": 1.572,
                r"(if|mf)_dip_act$": 0.37,
                r"rf_mcp_act$": 0.136,
                r"rf_pip_act$": 1.428,
                r"rf_dip_act$": 0.788,
                r"th_cmc_act$": 0.862,
                r"th_axl_act$": 1.036,
                r"th_mcp_act$": 1.326,
                r"th_ipl_act$": 1.414,
            },
            "pinch": {
                r"if_mcp_act$": 1.0,
                r"if_(pip|dip)_act$": 0.6,
                r"(mf|rf)_mcp_act$": 1.8,
                r"(mf|rf)_(pip|dip)_act$": 1.5,
                r"th_cmc_act$": 1.3,
                r"th_axl_act$": 1.5,
                r"th_mcp_act$": 0.3,
                r"th_ipl_act$": 0.5,
            },
            "tip_pinch": {
                r"if_mcp_act$": 1.0,
                r"if_(pip|dip)_act$": 0.6,
                r"th_cmc_act$": 1.3,
                r"th_axl_act$": 1.5,
                r"th_mcp_act$": 0.3,
                r"th_ipl_act$": 0.5,
            },
        },
    ),
    "sharpa": HandSpec(
        name="sharpa",
        retarget=RetargetSpec(scale=1.07),
        grasp_offset=(0.097, -0.001, 0.0675),
        bar_yaw=-0.4,
        # RetrieveCup (the rim): at the Shadow hand's place its fingers close on the rim's
        # far edge and the cup swings out; 3 cm back along the fingers they pinch the wall.
        # Searched on 6 episodes (0.02 m grid): floating 1/6 -> 6/6, fr3 and ur10e 6/6.
        shifts={"rim": (-0.03, 0.0, 0.0)},
        # InsertPen (the pen pinched 2 cm off its middle, then turned tip-down): with the
        # long part out past the fingertips the pen slides out of the tips in the turn;
        # back under the palm it stays. Floating, episodes 0-11: 6 -> 12 of 12 (the Shadow
        # hand 9 -> 6 and the Wuji hand 12 -> 11 that way round: theirs stay unset).
        hang_back=True,
        collection="sharpa_wave",
        sides={"right": _sharpa_side("right"), "left": _sharpa_side("left")},
        synergies={
            "open": {},
            "power": {
                r"_(index|middle|ring|pinky)_MCP_FE_ctrl$": 0.87,
                r"_(index|middle|ring|pinky)_(PIP|DIP)_ctrl$": 1.44,
                r"_thumb_CMC_FE_ctrl$": 0.97,
                r"_thumb_CMC_AA_ctrl$": -0.26,
                r"_thumb_MCP_FE_ctrl$": 0.82,
                r"_thumb_IP_ctrl$": 1.12,
            },
            "pinch": {
                r"_index_MCP_FE_ctrl$": 0.9,
                r"_index_(PIP|DIP)_ctrl$": 0.6,
                r"_(middle|ring|pinky)_MCP_FE_ctrl$": 1.5,
                r"_(middle|ring|pinky)_(PIP|DIP)_ctrl$": 1.4,
                r"_thumb_CMC_FE_ctrl$": 1.3,
                r"_thumb_CMC_AA_ctrl$": 0.3,
                r"_thumb_MCP_FE_ctrl$": 0.4,
                r"_thumb_IP_ctrl$": 0.4,
            },
            "tip_pinch": {
                r"_index_MCP_FE_ctrl$": 0.9,
                r"_index_(PIP|DIP)_ctrl$": 0.6,
                r"_thumb_CMC_FE_ctrl$": 1.3,
                r"_thumb_CMC_AA_ctrl$": 0.1,
                r"_thumb_MCP_FE_ctrl$": 0.3,
                r"_thumb_IP_ctrl$": 0.3,
            },
        },
    ),
    "inspire": HandSpec(
        name="inspire",
        # Short fingers on a long palm: scaled by its wrist-to-middle-tip (15.7 cm) over a
        # human's 18 cm instead of by finger length (which gives 0.61).
        retarget=RetargetSpec(scale=0.87),
        grasp_offset=(0.108, -0.015, 0.049),
        bar_yaw=0.4,
        # RetrieveCup (the rim): at the Shadow hand's place the cup, held tilted 10-15 deg,
        # slips round the thumb (pressed into the rim) on the arms' carry and is set down
        # too tilted to stand. 1.5 cm along hand -y: searched on fr3_inspire (x, y, z
        # +-0.01, then y -0.005..-0.02; episodes 0-7: y 0 4 of 8, -0.005 5, -0.01 and
        # -0.02 8); episodes 0-19 on the FR3 9 -> 17 of 20; episodes 0-11 floating 12 of
        # 12, UR10e 8 -> 10, xArm7 8 -> 11.
        shifts={"rim": (0.0, -0.015, 0.0)},
        collection="inspire_hand",
        sides={"right": _inspire_side("right"), "left": _inspire_side("left")},
        synergies={
            "open": {},
            "power": {
                r"(index|middle|ring|pinky)_proximal_drive$": 1.38,
                r"(index|middle|ring|pinky)_distal_drive$": 0.87,
                r"thumb_proximal_1_drive$": 1.2,
                r"thumb_proximal_2_drive$": 0.66,
                r"thumb_(middle|distal)_drive$": 0.0,
            },
            # Declared, not derived: this hand's open thumb stands out from the palm, so
            # a vessel held in the curled fingers rolls out over it. The thumb turns
            # across the palm, a little flexed (a wall, not a clamp, at the plans' twofold
            # squeeze), and the index stays open: both would otherwise lie at a tipped
            # cup's rim (searched on GraspCup, 4 of 4 held clear of the rim).
            "hook": {
                r"(middle|ring|pinky)_proximal_drive$": 1.38,
                r"(middle|ring|pinky)_distal_drive$": 0.87,
                r"thumb_proximal_1_drive$": 0.65,
                r"thumb_proximal_2_drive$": 0.15,
            },
            "pinch": {
                r"index_proximal_drive$": 0.9,
                r"index_distal_drive$": 0.9,
                r"(middle|ring|pinky)_(proximal|distal)_drive$": 1.6,
                r"thumb_proximal_1_drive$": 1.3,
                r"thumb_(proximal_2|middle|distal)_drive$": 0.4,
            },
            "tip_pinch": {
                r"index_proximal_drive$": 0.9,
                r"index_distal_drive$": 0.9,
                r"thumb_proximal_1_drive$": 1.3,
                r"thumb_(proximal_2|middle|distal)_drive$": 0.3,
            },
        },
    ),
    "wuji": HandSpec(
        name="wuji",
        retarget=RetargetSpec(scale=1.0),
        grasp_offset=(0.105, -0.022, 0.03),
        # GraspPan, floating: 0 -> 7 of 8 episodes at -0.6 and -0.7 (0.1 rad grid, -1.2..0.8)
        bar_yaw=-0.7,
        # The hammer: at the Shadow hand's place the lifted head tips the hammer ~30 deg in
        # the grip and it falls out during the carry; 2.3 cm towards the wrist, 0.7 cm
        # sideways, 1.2 cm further from the palm it holds. Random search (16 candidates,
        # floating, episodes 0, 1, 3, 6, 7, 8: 0 -> 5 of 6), checked on episodes 9-16:
        # 3 -> 7 of 8. On the arms 1.5 cm further still from the palm (z 0.012 -> 0.027):
        # a grid of +-0.01 on each axis on fr3_wuji (episodes 0-7: 2 of 8; z 0.022 and
        # 0.032 6, y +0.01 4, the rest 0), then z 0.027 on 20 episodes: FR3 4 -> 14,
        # floating 18 -> 18; 12 episodes: UR10e 4 -> 11, xArm7 0 -> 4.
        # The kettle: hooked 1 cm further along hand -y on its handle bar, the floating hand
        # lifts and pours it in 7 of episodes 0-7 (3 at the Shadow hand's place), 9 of
        # 8-19 (5): a grid of +-0.01 on each axis, then y -0.005..-0.02 (4, 7, 3, 2 of 8).
        # The arms as before (12 episodes: FR3 2 -> 3, UR10e 11 -> 10, xArm7 8 -> 8).
        shifts={"tool": (-0.023, 0.007, 0.027), "handle": (0.0, -0.01, 0.0)},
        collection="wuji_hand",
        sides={"right": _wuji_side("right"), "left": _wuji_side("left")},
        synergies={
            "open": {},
            # A hook grasp: some knuckle flexion, strongly curled distal joints, so the
            # weak fingers (forcerange ~0.2-0.6 Nm) press with short lever arms. Values
            # (and the offset) searched like Allegro's, on the floating and xArm7 mounts.
            "power": {
                r"finger[2-5]_joint1_actuator$": 0.535,
                r"finger[2-5]_joint[34]_actuator$": 2.002,
                r"finger1_joint1_actuator$": 1.742,
                r"finger1_joint2_actuator$": 1.707,
                r"finger1_joint[34]_actuator$": 2.06,
            },
            "pinch": {
                r"finger2_joint1_actuator$": 0.9,
                r"finger2_joint[34]_actuator$": 0.6,
                r"finger[3-5]_joint1_actuator$": 1.5,
                r"finger[3-5]_joint[34]_actuator$": 1.4,
                r"finger1_joint1_actuator$": 1.3,
                r"finger1_joint2_actuator$": 0.6,
                r"finger1_joint[34]_actuator$": 0.4,
            },
            # A ring pinch: the index, little bent at the knuckle, curls its tip down onto
            # the thumb's (its last joint straight), the two about level (they meet at
            # 0.86 closure and press past it). Found by a random search over the tips'
            # closing path (3 cm apart at the preshape, touching at the end) and then over
            # InsertPen's expert (the pen held tip-down); the first guess's tips passed 7 mm
            # apart, and other candidates' let the pen slide out once tip-down.
            "tip_pinch": {
                r"finger2_joint1_actuator$": 0.42,
                r"finger2_joint2_actuator$": -0.09,
                r"finger2_joint3_actuator$": 1.5,
                r"finger2_joint4_actuator$": 1.11,
                r"finger1_joint1_actuator$": 0.82,
                r"finger1_joint2_actuator$": 0.57,
                r"finger1_joint3_actuator$": 1.29,
                r"finger1_joint4_actuator$": -0.4,
            },
        },
    ),
}

# `hook` is derived for every hand (power fingers, open thumb) unless its HandSpec
# declares one (a hand whose open thumb lets a held vessel roll out).
SYNERGIES = ("open", "power", "pinch", "tip_pinch", "hook")

"""The ball pusher (PushSmallSphereObstacleSlope). On an arm the fingertip trails the fast
descent behind the ball by more than a stuck push trails its command, so the push waits
for it to settle (begun at once it read as stuck every time: UR10e and xArm7 0.00); a ball
that veers off is steered back before the posts; a hand's own contacts do not kick it."""

import numpy as np
import torch

from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.experts.adapter import tips_in_palm_frame
from dexbench.experts.path_push import BLOCKED, SETTLED, Phase
from dexbench.tasks.registry import make_env


def _start(embodiment: str, episodes: list[int]):
    """The ball-push task on `embodiment` at these evaluation episodes, and its expert."""
    env = make_env("PushSmallSphereObstacleSlope", embodiment, num_envs=len(episodes), seed=0,
                   nthread=1)
    env.reset_to(torch.arange(len(episodes)), eval_keys(0, episodes))
    expert = make_expert(env)
    expert.reset(torch.arange(len(episodes)))
    return env, expert


def _run(env, expert, watch=None) -> np.ndarray:
    """(N,) which episodes the expert solves, run to their ends; `watch(ended)` is called
    after every step."""
    ended = np.zeros(env.num_envs, dtype=bool)
    solved = np.zeros(env.num_envs, dtype=bool)
    for _ in range(1200):
        _, _, terminated, truncated, _ = env.step(expert.act())
        solved |= terminated.numpy() & ~ended
        ended |= (terminated | truncated).numpy()
        if watch is not None:
            watch(ended)
        if ended.all():
            break
    return solved


def test_arm_pushes_the_ball_up_the_slope_once_its_fingertip_settles():
    env, expert = _start("ur10e_sharpa", [0])
    start = env.task.past(env.view)[0].item()
    lags, pushes, aborted = [], [], 0
    for _ in range(300):
        before = int(expert.phase[0])
        env.step(expert.act())
        palm, rot, _ = tips_in_palm_frame(env, expert._palm, expert._tips)
        tip = palm[0] + rot[0] @ expert.offsets[0, expert.lead[0]]
        lag = float(np.linalg.norm(expert.pos[0] - tip))
        if before == Phase.DOWN:
            lags.append(lag)
        if before != Phase.PUSH and expert.phase[0] == Phase.PUSH:
            pushes.append(lag)
        aborted += before == Phase.PUSH and expert.phase[0] == Phase.ABOVE
    assert max(lags) > BLOCKED, "the arm trails its descent as far as a stuck push"
    assert pushes and pushes[0] < SETTLED + 0.005, "the push began with the fingertip behind"
    assert aborted == 0, "a push read as stuck"
    assert env.task.past(env.view)[0].item() > start + 0.15, "the ball went up the slope"


def test_arm_keeps_the_ball_on_its_line_between_the_posts():
    """xArm7 episode 2: the fingertip sat ~5 mm across the push from its command, the
    ball weaved 6 cm off the centre line onto a post and stayed jammed there; with the
    offset taken out of the command it goes between the posts and over the crest."""
    env, expert = _start("xarm7_sharpa", [2])
    for _ in range(600):
        env.step(expert.act())
        if env.task.success(env.view)[0]:
            break
    assert env.task.success(env.view)[0]


def test_ball_that_veers_off_is_steered_back_before_the_posts():
    """Floating Inspire, episodes 10, 16, 17, 18: the ball veers off its line as it meets
    the slope; steered at a point 10 cm along the line it came back too late and ran onto
    a post (0 of 4), steered at 5 cm it goes between them and over the crest."""
    episodes = [10, 16, 17, 18]
    env, expert = _start("floating_inspire", episodes)
    solved = torch.zeros(len(episodes), dtype=torch.bool)
    for _ in range(1200):
        env.step(expert.act())
        solved |= env.task.success(env.view).cpu()
        if solved.all():
            break
    assert solved.all(), f"solved {solved.tolist()}"


def test_leap_pushes_the_ball_over_the_crest_without_kicking_it():
    """Two LEAP faults, each enough to fail this: its model's own contacts (solref 1e-4 s,
    solimp 0.999) are stiffer than the 4 ms step resolves, and its fingertip, pressing the
    ball onto the table, kicked it off at 3.7, 7.6 and 2.4 m/s in these episodes ('solving'
    two of them so); with the Shadow hand's softness (`HandSpec.soft_contacts`) the ball
    rolls, but steered by the tip site, 3 cm behind and 1.6 cm beside the finger's front,
    it ran off its line (none solved). Steered by the finger's front: all three, the
    ball under 1.5 m/s."""
    env, expert = _start("floating_leap", [0, 2, 7])
    last = env.view.body_pos("sphere").numpy().copy()
    fastest = np.zeros(env.num_envs)

    def watch(ended: np.ndarray) -> None:
        nonlocal last, fastest
        ball = env.view.body_pos("sphere").numpy()
        speed = np.linalg.norm(ball - last, axis=1) / env.control_dt
        last = ball.copy()
        on_table = ball[:, 2] > 0.6  # a ball rolled off the edge falls at ~3.4 m/s
        fastest = np.where(ended | ~on_table, fastest, np.maximum(fastest, speed))

    solved = _run(env, expert, watch)
    assert fastest.max() < 1.5, f"ball speeds {fastest.round(2).tolist()} m/s"
    assert solved.all(), f"solved {solved.tolist()}"


def test_wuji_pushes_the_ball_with_its_finger_just_clear_of_the_table():
    """The pushing finger's lowest point rides `CLEAR` above the ball's bottom, measured on
    the finger's geoms: measured on their bounding boxes instead, it rode 2.6-5.5 mm
    higher by hand (the Wuji finger 4.8 mm), and floating Wuji solved 2 of episodes 0-9,
    none of these three."""
    solved = _run(*_start("floating_wuji", [1, 3, 5]))
    assert solved.all(), solved

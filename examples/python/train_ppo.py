"""Trains Stable-Baselines3's PPO (CPU, its default MLP policy) to dock on ``rpod/Docking-v0``,
then evaluates it on 100 seeded episodes and plots the learning curve.

    pip install 'rpod[gym]' stable-baselines3 matplotlib
    nice -n 10 python examples/python/train_ppo.py --minutes 60 --out runs/ppo

Everything about the task is the environment's defaults (``rpod.gym.DockingEnv``: 5 N and
0.2 N·m of authority held for 0.5 s, the observation scaled to order one, progress and
alignment rewards as differences of a potential, +10 on LATCHED; see ``docs/python.md``).
PPO runs at Stable-Baselines3's defaults (``MlpPolicy``, learning rate 3e-4, 10 epochs of
64-sample minibatches, γ = 0.99, λ = 0.95, clip 0.2) with three changes, each a standard knob of
the library: ``n_steps`` 512 per worker (1024 per update with two workers, half the default's 2048:
an hour on this machine gives about a hundred thousand steps, and more updates of fewer samples
learn sooner); the policy's initial action noise ``log_std_init`` −1 (a standard deviation of
0.37 of full scale instead of 1: at 1 the clipped Gaussian is nearly bang-bang, a random walk of
about 0.07 m/s over an episode, larger than the mechanism's capture speeds, so exploration
rarely lands); and the rewards scaled by their running standard deviation (``VecNormalize``,
rewards only: the observation is already of order one) so that the +10 of a latch and the
centimetre progress terms share one scale for the value function. A curriculum over the start distance (the
environment's ``set_ranges``): starts 25–40 cm above the seat (the cone's tip 5–20 cm above the
slot's mouth), widened to 30–70 cm, 40–100 cm and
the environment's default 50–150 cm each time 60 % of the last rollout's episodes latched; the
evaluation is on the default ranges.

Outputs in ``--out``: ``curve.csv`` (one row per rollout: environment steps, wall-clock
minutes, the mean return and the LATCHED fraction of the training episodes that ended in it),
``train.json``, ``eval.json`` (the evaluation: seeds, outcomes, success rate; in
``--eval-workers`` processes), ``model.zip`` (the policy, ~150 kB) and ``learning_curve.png``.
``--evaluate-only`` evaluates and plots a model trained earlier.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import pathlib
import time

import numpy as np


def make_env(seed: int):
    def thunk():
        import gymnasium as gym
        from stable_baselines3.common.monitor import Monitor

        import rpod.gym  # noqa: F401  (registers rpod/Docking-v0)

        env = gym.make("rpod/Docking-v0")
        env = Monitor(env, info_keywords=("is_success", "docking_state"))
        env.reset(seed=seed)
        return env

    return thunk


def _evaluate_seeds(args):
    """Deterministic policy on seeded episodes (one worker): an outcome per seed."""
    model_path, seeds, deadline = args
    import gymnasium as gym
    from stable_baselines3 import PPO

    import rpod.gym  # noqa: F401

    model = PPO.load(model_path, device="cpu")
    env = gym.make("rpod/Docking-v0")
    out = []
    for seed in seeds:
        if deadline is not None and time.time() > deadline:
            break
        obs, _ = env.reset(seed=seed)
        ret = 0.0
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, r, term, trunc, info = env.step(action)
            ret += r
            if term or trunc:
                break
        out.append(
            {
                "seed": seed,
                "docking_state": info["docking_state"],
                "latched": bool(info["is_success"]),
                "departed": bool(info["departed"]),
                "collision": info["reward_terms"]["collision"] < 0,
                "t_s": info["t_s"],
                "return": ret,
            }
        )
    env.close()
    return out


def evaluate(model_path, episodes: int, first_seed: int, workers: int, minutes=None):
    """The seeds first_seed … first_seed + episodes − 1, split over `workers` processes
    (seed k to worker k mod workers); with `minutes`, the episodes finished by then."""
    import multiprocessing as mp

    seeds = list(range(first_seed, first_seed + episodes))
    deadline = None if minutes is None else time.time() + 60.0 * minutes
    jobs = [(str(model_path), seeds[k::workers], deadline) for k in range(workers)]
    with mp.get_context("forkserver").Pool(workers) as pool:
        parts = pool.map(_evaluate_seeds, jobs)
    return sorted((r for p in parts for r in p), key=lambda r: r["seed"])


def plot(curve_csv: pathlib.Path, png: pathlib.Path, eval_rate: float, eval_n: int, title: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(csv.DictReader(open(curve_csv)))
    steps = np.array([float(r["env_steps"]) for r in rows])
    minutes = np.array([float(r["wall_min"]) for r in rows])
    ret = np.array([float(r["mean_return"]) if r["mean_return"] else np.nan for r in rows])
    succ = np.array([float(r["latched_frac"]) if r["latched_frac"] else np.nan for r in rows])
    stage = np.array([int(r["stage"]) for r in rows])
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for j, k in enumerate(np.nonzero(np.diff(stage))[0]):
        for a_ in ax:
            a_.axvline(steps[k + 1] / 1e3, color="0.6", lw=0.8)
        # Stages can start a few rollouts apart: each label one line above the last.
        ax[0].text(steps[k + 1] / 1e3, 3 + 7 * j, f" stage {stage[k + 1]}", fontsize=7,
                   color="0.4")
    ax[0].plot(steps / 1e3, 100 * succ, color="tab:green", marker="o", ms=3,
               label="training episodes of each rollout")
    if np.isfinite(eval_rate):
        ax[0].axhline(100 * eval_rate, color="k", ls="--", lw=1,
                      label=f"evaluation, {eval_n} seeded episodes: {100 * eval_rate:.0f} %")
    ax[0].axhline(80, color="tab:red", ls=":", lw=1, label="target 80 %")
    ax[0].set_xlabel("environment steps (thousands; one step = 0.5 s)")
    ax[0].set_ylabel("training episodes LATCHED, %")
    ax[0].set_ylim(-2, 102)
    ax[0].legend(loc="lower right", fontsize=8)
    if len(steps) >= 2:
        top = ax[0].secondary_xaxis(
            "top",
            functions=(lambda s: np.interp(s, steps / 1e3, minutes),
                       lambda m: np.interp(m, minutes, steps / 1e3)),
        )
        top.set_xlabel("wall-clock minutes")
    ax[1].plot(steps / 1e3, ret, color="tab:blue")
    ax[1].set_xlabel("environment steps (thousands)")
    ax[1].set_ylabel("mean episode return")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=60.0, help="wall-clock training budget")
    ap.add_argument("--timesteps", type=int, default=2_000_000, help="upper bound on env steps")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-envs", type=int, default=2, help="worker processes (one per core)")
    ap.add_argument("--eval-episodes", type=int, default=100)
    ap.add_argument("--eval-seed", type=int, default=100_000, help="first evaluation seed")
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/ppo"))
    ap.add_argument("--plot", type=pathlib.Path, default=None, help="copy of the plot")
    ap.add_argument("--no-curriculum", dest="curriculum", action="store_false",
                    help="train on the default start ranges from the first step")
    ap.add_argument("--log-std-init", type=float, default=-1.0,
                    help="the policy's initial log standard deviation (SB3's default: 0)")
    ap.add_argument("--no-norm-reward", dest="norm_reward", action="store_false",
                    help="train on the raw rewards (no VecNormalize)")
    ap.add_argument("--eval-workers", type=int, default=2)
    ap.add_argument("--eval-minutes", type=float, default=None,
                    help="stop the evaluation after this (the episodes done are reported)")
    ap.add_argument("--evaluate-only", action="store_true",
                    help="evaluate OUT/model.zip (trained earlier) and plot; no training")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw OUT/learning_curve.png from OUT/curve.csv and eval.json")
    a = ap.parse_args()
    if a.replot:
        replot(a)
        return
    if a.evaluate_only:
        finish_evaluation(a)
        return

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

    torch.set_num_threads(1)
    a.out.mkdir(parents=True, exist_ok=True)
    fns = [make_env(a.seed * 1000 + i) for i in range(a.n_envs)]
    venv = SubprocVecEnv(fns, start_method="forkserver") if a.n_envs > 1 else DummyVecEnv(fns)
    if a.norm_reward:
        venv = VecNormalize(venv, norm_obs=False, norm_reward=True, gamma=0.99)
    model = PPO("MlpPolicy", venv, n_steps=512, seed=a.seed, verbose=0, device="cpu",
                policy_kwargs={"log_std_init": a.log_std_init})
    stages = [(0.25, 0.4), (0.3, 0.7), (0.4, 1.0), None]  # None: the environment's default
    default_range = venv.get_attr("ranges")[0]["start_range_m"]
    stage = [0]

    def set_stage(k):
        stage[0] = k
        r = stages[k] if stages[k] is not None else default_range
        venv.env_method("set_ranges", start_range_m=r)

    set_stage(0 if a.curriculum else len(stages) - 1)

    t0 = time.perf_counter()
    curve_path = a.out / "curve.csv"

    class Curve(BaseCallback):
        """One row per rollout; stops at the wall-clock budget."""

        def _on_training_start(self):
            self.f = open(curve_path, "w", newline="")
            self.w = csv.writer(self.f)
            self.w.writerow(["env_steps", "wall_min", "episodes", "mean_return", "latched_frac",
                             "stage"])
            self.episodes = 0
            self.window = []

        def _on_step(self):
            for info in self.locals["infos"]:
                ep = info.get("episode")
                if ep is not None:
                    self.episodes += 1
                    self.window.append((ep["r"], bool(info.get("is_success"))))
            return time.perf_counter() - t0 < 60.0 * a.minutes

        def _on_rollout_end(self):
            w = self.window
            self.w.writerow([
                self.num_timesteps,
                f"{(time.perf_counter() - t0) / 60:.3f}",
                self.episodes,
                f"{np.mean([r for r, _ in w]):.4f}" if w else "",
                f"{np.mean([s for _, s in w]):.4f}" if w else "",
                stage[0],
            ])
            self.f.flush()
            print(f"{self.num_timesteps:8d} steps {(time.perf_counter() - t0) / 60:6.1f} min "
                  f"episodes {self.episodes:6d} return "
                  f"{np.mean([r for r, _ in w]) if w else float('nan'):7.2f} latched "
                  f"{100 * np.mean([s for _, s in w]) if w else float('nan'):5.1f} % "
                  f"stage {stage[0]}", flush=True)
            if w and np.mean([s for _, s in w]) >= 0.6 and stage[0] < len(stages) - 1:
                set_stage(stage[0] + 1)
            self.window = []

        def _on_training_end(self):
            self.f.close()

    model.learn(total_timesteps=a.timesteps, callback=Curve())
    train_min = (time.perf_counter() - t0) / 60.0
    model.save(a.out / "model.zip")
    venv.close()
    (a.out / "train.json").write_text(json.dumps({
        "seed": a.seed, "n_envs": a.n_envs, "training_minutes": round(train_min, 2),
        "env_steps": int(model.num_timesteps), "log_std_init": a.log_std_init,
        "norm_reward": a.norm_reward, "curriculum": a.curriculum, "final_stage": stage[0]},
        indent=1))
    finish_evaluation(a)


def title_of(train: dict) -> str:
    return (f"PPO (Stable-Baselines3, CPU) on rpod/Docking-v0, seed {train['seed']}: "
            f"{train['env_steps']} steps in {train['training_minutes']:.0f} min on "
            f"{train['n_envs']} workers")


def replot(a):
    """Redraws the plot of a finished run (`curve.csv`, `train.json`, `eval.json`)."""
    summary = json.loads((a.out / "eval.json").read_text())
    png = a.out / "learning_curve.png"
    plot(a.out / "curve.csv", png, summary["latched_rate"], summary["eval_episodes_done"],
         title_of(summary))
    if a.plot is not None:
        a.plot.parent.mkdir(parents=True, exist_ok=True)
        a.plot.write_bytes(png.read_bytes())


def finish_evaluation(a):
    """Evaluates `a.out/model.zip` on the seeded episodes, writes eval.json and the plot."""
    train = json.loads((a.out / "train.json").read_text())
    results = evaluate(a.out / "model.zip", a.eval_episodes, a.eval_seed, a.eval_workers,
                       a.eval_minutes)
    rate = float(np.mean([r["latched"] for r in results])) if results else float("nan")
    summary = dict(train)
    summary.update({
        "eval_first_seed": a.eval_seed,
        "eval_episodes_asked": a.eval_episodes,
        "eval_episodes_done": len(results),
        "latched_rate": rate,
        "outcomes": {s: sum(r["docking_state"] == s for r in results)
                     for s in sorted({r["docking_state"] for r in results})},
        "departed": sum(r["departed"] for r in results),
        "collisions": sum(r["collision"] for r in results),
        "mean_time_to_end_s": float(np.mean([r["t_s"] for r in results])) if results else None,
        "episodes": results,
    })
    (a.out / "eval.json").write_text(json.dumps(summary, indent=1))
    title = title_of(train)
    png = a.out / "learning_curve.png"
    plot(a.out / "curve.csv", png, rate, len(results), title)
    if a.plot is not None:
        a.plot.parent.mkdir(parents=True, exist_ok=True)
        a.plot.write_bytes(png.read_bytes())
    print(f"trained {train['training_minutes']:.1f} min, {train['env_steps']} env steps; "
          f"evaluation: {100 * rate:.0f} % LATCHED of {len(results)} seeded episodes "
          f"(of {a.eval_episodes} asked) {summary['outcomes']}")
    print(f"outputs in {os.fspath(a.out)}")


if __name__ == "__main__":
    main()

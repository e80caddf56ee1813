"""Seeded generator of BioTac-like sequences grounded in the sensor's physics, and the
preprocessing that turns raw frames into the detector's input exactly as graspd does.

Nothing here is fitted to or copied from the real recordings; the numeric ranges below were set
by hand from the statistics that `calibrate.py` measures on samples 1-10 of each material of
../shared/testdata/tactile/biotac_slide (see MODEL_CARD.md, "Calibration"). Every range cites
the statistic it was set from.

Sensor model (classic SynTouch BioTac, one frame per 10 ms):

* **pdc** (static fluid pressure) rises linearly with the normal force F:
  pdc = g_p * F * creep(t) (g_p counts/N). The real recordings are baseline-subtracted upstream
  and their pdc decays toward 0 while the finger stays pressed (median pdc 25 at median fz
  2.4 N, and < 5 after ~6 s on paper and plastic), so `creep` is a per-sequence exponential
  decay with time constant tau_creep (or none).
* **electrodes** (impedance between the core electrodes and the skin): the skin is pressed
  toward the core under a contact patch centred at a random location on the electrode layout
  (service/sensors/biotac.toml); each electrode's tared deviation is
  g_e * F * exp(-d^2 / (2 r^2)) * creep(t), d its distance from the contact centre, r the
  contact radius, growing with F^(1/3) (Hertz) and larger on compliant materials (foam). Raw
  BioTac impedance *falls* under pressure, so raw counts are baseline - deviation.
* **pac** (dynamic pressure, 22 samples per frame at 2.2 kHz): a level (AC-coupled channel,
  transients at make/break of contact), white noise, and while sliding a texture vibration:
  a sinusoid at f = v / lambda (lambda the material's texture period) plus broadband
  stick-slip noise, both scaled by the material's roughness and the sliding speed.
* **tdc / tac** (temperature and heat flow): the warm sensor loses heat into the object at a
  rate set by the contact's thermal effusivity ratio e_obj / (e_obj + e_skin): metal draws heat
  fastest, foam slowest (effusivities: steel ~14000, polypropylene ~700, paper ~500,
  polymer foam ~60 W s^0.5 m^-2 K^-1; sensor skin + fluid ~900). tdc changes by
  A_T * ratio * (1 - exp(-t / tau_T)); tac, the AC-coupled heat-flow channel, shows a transient
  A_tac * ratio * exp(-t / tau_tac) after contact starts.
* Phases follow the recordings' slides: non-contact -> press (contact) -> slide (slip) ->
  optionally stop (contact) -> optionally release (non-contact). Some sequences start already
  pressed and sliding, as the recordings do.

Labels follow the recordings' README: contact iff F >= 0.5 N, slip iff contact and the sliding
speed >= 5 mm/s (0.005 m/s).

Two output styles:
* "raw": 12-bit-like counts with per-channel baselines in the thousands and falling
  electrodes, tared by graspd with the mean of the first 50 frames (TareConfig::default()).
* "pretared": like the dexrob recordings, baseline-subtracted and clipped at 0 upstream,
  rising electrodes (TareConfig::pretared()).
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

MATERIALS = ["paper", "foam", "plastic", "metal"]
EVENTS = ["non_contact", "contact", "slip"]
CONTACT_FORCE_N = 0.5
SLIP_SPEED = 0.005
FRAME_DT = 0.01
PAC_PER_FRAME = 22
BASELINE_FRAMES = 50  # TareConfig::default()
WINDOW = 32  # l (Table 6.1)
STRIDE = 3  # k (Table 6.1)
FEATURES = ["pdc", "pac", "pac_vibration", "tdc", "tac"] + [f"e{i}" for i in range(1, 20)]

# Physical parameters per material. `effusivity` in W s^0.5 m^-2 K^-1 (handbook values);
# `roughness` scales the slip vibration; `texture_mm` is the texture's spatial period;
# `compliance` scales the contact radius (soft foam wraps the fingertip).
# roughness was set so that the median slip vibration of the generated data sits near the
# recordings' per-class median pac vibration (calibration.json "real.pac_vibration",
# samples 1-10): plastic 4.7, paper 5.8, metal 6.4, foam 7.7 counts over a ~3-count floor.
MATERIAL_PHYSICS = {
    "paper": dict(effusivity=500.0, roughness=1.0, texture_mm=(0.3, 1.0), compliance=1.1),
    "foam": dict(effusivity=60.0, roughness=1.6, texture_mm=(0.5, 2.0), compliance=1.6),
    "plastic": dict(effusivity=700.0, roughness=0.65, texture_mm=(0.2, 0.8), compliance=1.0),
    "metal": dict(effusivity=14000.0, roughness=1.15, texture_mm=(0.1, 0.5), compliance=0.9),
}
SKIN_EFFUSIVITY = 900.0


def load_layout(path: str | None = None) -> np.ndarray:
    """Electrode centres (mm) from service/sensors/biotac.toml (data, not code)."""
    if path is None:
        here = os.path.dirname(os.path.abspath(__file__))
        path = os.path.join(here, "..", "..", "service", "sensors", "biotac.toml")
    text = open(path, encoding="utf-8").read()
    start = text.index("electrodes")
    body = text[text.index("[", start) + 1 :]
    pts = []
    for line in body.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("]") and not line.startswith("],"):
            break
        if line.startswith("["):
            x, y = line.strip("[],").split(",")[:2]
            pts.append((float(x), float(y)))
    return np.array(pts)


@dataclass
class Sequence:
    """One generated recording: raw frames as in a `_bio.csv` plus per-frame labels."""

    material: str
    style: str  # "raw" or "pretared"
    timestamp: np.ndarray  # [T]
    tdc: np.ndarray
    tac: np.ndarray
    pdc: np.ndarray
    pac: np.ndarray  # [T, 22]
    electrodes: np.ndarray  # [T, 19]
    labels: np.ndarray  # [T] in 0..2 (EVENTS)
    force: np.ndarray  # [T] N
    speed: np.ndarray  # [T] m/s


def _phases(rng: np.random.Generator, style: str):
    """Force (N) and speed (m/s) profiles, 100 Hz."""
    f_hold = rng.uniform(0.8, 6.0)  # real fz during the slides: 5-95 % 1.1-6.2 N
    v_slide = rng.uniform(0.006, 0.05)  # real planar speed ~0.017-0.025 m/s, widened
    segs = []  # (duration s, force start, force end, speed)
    starts_pressed = style == "pretared" and rng.random() < 0.35
    if not starts_pressed:
        lead = rng.uniform(0.3, 1.2) + (BASELINE_FRAMES * FRAME_DT if style == "raw" else 0.0)
        segs.append((lead, 0.0, 0.0, 0.0))
        segs.append((rng.uniform(0.1, 0.4), 0.0, f_hold, 0.0))  # press
        segs.append((rng.uniform(0.3, 1.5), f_hold, f_hold, 0.0))  # hold
    else:
        segs.append((rng.uniform(0.0, 0.3), f_hold, f_hold, 0.0))
    n_slides = 1 + int(rng.random() < 0.4)
    for _ in range(n_slides):
        # Slides last 1-8 s: the recordings' arm moves from their first ~0.1 s to their end (8 s)
        # (calibration.json "real.phases", samples 1-10, label-free: arm speed only).
        segs.append((rng.uniform(1.0, 8.0), f_hold, f_hold * rng.uniform(0.8, 1.25), v_slide))
        f_hold = segs[-1][2]
        if rng.random() < 0.6:
            segs.append((rng.uniform(0.3, 1.2), f_hold, f_hold, 0.0))  # stop, still pressed
    if rng.random() < 0.6:
        segs.append((rng.uniform(0.1, 0.3), f_hold, 0.0, 0.0))  # release
        segs.append((rng.uniform(0.3, 1.2), 0.0, 0.0, 0.0))
    force, speed = [], []
    for dur, f0, f1, v in segs:
        n = max(1, int(round(dur / FRAME_DT)))
        force.append(np.linspace(f0, f1, n))
        # Speed ramps in and out over ~50 ms like an arm's velocity profile.
        s = np.full(n, v)
        if v > 0:
            r = min(5, n // 2)
            s[:r] *= np.linspace(0.2, 1, r)
            s[n - r :] *= np.linspace(1, 0.2, r)
        speed.append(s)
    force = np.concatenate(force)
    speed = np.concatenate(speed) * rng.uniform(0.85, 1.15, size=1)
    # Force fluctuates while sliding (stick-slip, uneven surface).
    force = np.clip(force * (1 + 0.05 * np.sin(np.cumsum(rng.uniform(0.05, 0.3, len(force))))), 0, None)
    return force, speed


def generate(rng: np.random.Generator, material: str, style: str, layout: np.ndarray) -> Sequence:
    phys = MATERIAL_PHYSICS[material]
    force, speed = _phases(rng, style)
    T = len(force)
    t = np.arange(T) * FRAME_DT
    contact = force >= 1e-6
    # Time since contact began (per frame), for creep and thermal transients.
    since = np.zeros(T)
    acc = 0.0
    for i in range(T):
        acc = acc + FRAME_DT if contact[i] else 0.0
        since[i] = acc
    # Creep / upstream re-zeroing of the static channels (recordings: pdc -> ~0 within ~6 s on
    # paper/plastic, slower on foam/metal). Half the sequences have none (a raw sensor).
    # Pretared: 80 % creep (the recordings' pdc decays in ~4 of 5 recordings: pooled median 73
    # counts in the first second, 36 at 3-4 s, 5 at 6-7 s while pressed); raw sensors: 30 %.
    tau_creep = rng.uniform(1.5, 8.0) if rng.random() < (0.8 if style == "pretared" else 0.3) else np.inf
    creep = np.exp(-since / tau_creep)
    gain = math.exp(rng.uniform(math.log(0.5), math.log(2.0)))  # sensor-to-sensor gain spread

    # pdc: real pdc 5-95 % 0-139 counts at 1.1-6.2 N, early frames 50-120 at ~2-3 N.
    g_p = rng.uniform(10.0, 25.0) * gain
    pdc = g_p * force * creep

    # Electrodes: Gaussian contact patch (real top-3 electrode mean ~0.6-1.0 x pdc).
    cx = rng.uniform(layout[:, 0].min(), layout[:, 0].max())
    cy = rng.uniform(layout[:, 1].min() * 0.7, layout[:, 1].max() * 0.7)
    drift = np.cumsum(rng.normal(0, 1, (T, 2)), axis=0) * 0.02 * (speed[:, None] > 0)
    r0 = rng.uniform(2.5, 4.5) * phys["compliance"]
    radius = r0 * np.cbrt(np.maximum(force, 1e-3) / 2.0)
    d2 = ((layout[None, :, 0] - (cx + drift[:, :1])) ** 2
          + (layout[None, :, 1] - (cy + drift[:, 1:])) ** 2)
    g_e = rng.uniform(8.0, 18.0) * gain
    ele = g_e * force[:, None] * np.exp(-d2 / (2 * radius[:, None] ** 2)) * creep[:, None]
    # Stick-slip modulates the patch while sliding.
    sliding = speed >= SLIP_SPEED
    ele *= 1 + (0.04 * phys["roughness"] * rng.normal(size=(T, 1))) * sliding[:, None]

    # pac: per-frame level (AC-coupled: transients at make/break), noise, slip vibration.
    n = PAC_PER_FRAME
    dforce = np.diff(force, prepend=0.0)
    level = np.zeros(T)
    transient = 0.0
    for i in range(T):
        transient = transient * math.exp(-FRAME_DT / 0.15) + 40.0 * gain * abs(dforce[i]) / FRAME_DT * 0.05
        level[i] = transient
    level += np.cumsum(rng.normal(0, 2.0, T))  # slow wander of the AC-coupled level
    # While sliding the dynamic pressure also follows the low-frequency force fluctuations of the
    # slide (stick-slip, surface unevenness, the arm's own vibration): a heavy-tailed AR(1) jitter
    # of the frame level (coefficient 0.6 per frame). Set from the recordings' pac frame-mean
    # while the arm moves, all materials pooled (calibration.json "real.phases"): differences at
    # lag 1 / 3+ frames have std 80 / ~130 counts and the 1 s standard deviation has median 83
    # (25-75 % 43-108), versus ~11 in the previous generator.
    s_lvl = rng.uniform(30.0, 140.0) * gain ** 0.5
    jitter = np.zeros(T)
    innov = rng.standard_t(4, T) / math.sqrt(2.0) * s_lvl * math.sqrt(1 - 0.6 ** 2)
    for i in range(1, T):
        jitter[i] = 0.6 * jitter[i - 1] + innov[i]
    if style == "pretared":
        # The recordings' pac level sits on a low floor (per-recording 5th percentile of the frame
        # mean 7-30 counts, 1.2 % of samples at 0) with positive excursions only: their upstream
        # processing rectifies it, so the pretared style gets the one-sided jitter.
        jitter = np.abs(jitter) * 1.3
    level += jitter * np.sqrt(np.clip(speed / 0.02, 0, 2))
    sub_t = (np.arange(T)[:, None] * n + np.arange(n)[None, :]) / (n / FRAME_DT)
    floor = rng.uniform(2.0, 4.0)  # real quiet-frame pac vibration ~2.5-4 counts
    pac = level[:, None] + rng.normal(0, floor, (T, n))
    # Within-frame drift (the recordings show ramps of ~50 counts per frame after transients).
    pac += np.linspace(-0.5, 0.5, n)[None, :] * (np.diff(level, prepend=level[0]))[:, None]
    lam = rng.uniform(*phys["texture_mm"]) * 1e-3
    freq = speed / lam  # Hz
    phase = np.cumsum(freq) * FRAME_DT * 2 * math.pi
    # 0.85: pooled over all materials the recordings' vibration while the arm moves is
    # 3.0 / 4.3 / 5.7 / 7.6 / 12.5 counts (5/25/50/75/95 %), a little under the generated slides'.
    amp = 0.85 * phys["roughness"] * gain ** 0.5 * (speed / 0.02) ** 0.5 * sliding * (force / 2.5) ** 0.5
    sine = np.sin(phase[:, None] + 2 * math.pi * freq[:, None] * (sub_t - sub_t[:, :1]))
    pac += amp[:, None] * (rng.uniform(3.0, 5.0) * sine + rng.uniform(3.0, 6.0) * rng.normal(size=(T, n)))

    # Thermal: effusivity ratio sets how fast the sensor loses heat into the object.
    ratio = phys["effusivity"] / (phys["effusivity"] + SKIN_EFFUSIVITY)
    a_t = rng.uniform(3.0, 15.0)  # real tdc 5-95 % 0-22 counts
    tau_t = rng.uniform(2.0, 6.0)
    tdc = a_t * ratio * (1 - np.exp(-since / tau_t)) * contact
    a_tac = rng.uniform(60.0, 180.0)  # real early-contact tac 90-180 counts
    tau_tac = rng.uniform(0.4, 1.5)
    # While sliding the sensor keeps meeting fresh material at ambient temperature, so the heat
    # flow does not decay as in a static contact (the recordings' tac stays at tens of counts
    # through the slide): a sustained part growing with sqrt(speed).
    sustain = rng.uniform(0.2, 0.6) * np.sqrt(np.clip(speed / 0.02, 0, 4)) * sliding
    tac = a_tac * ratio * (np.exp(-since / tau_tac) + sustain) * contact
    # Slow ambient drift of both (the recordings' tdc drifts by -2..+7 counts over 8 s).
    tdc = tdc + np.cumsum(rng.normal(0, 0.05, T))
    tac = tac + rng.normal(0, 1.5, T)
    # pdc: sensor noise, plus the slide's force fluctuations (recordings, arm moving, pooled:
    # frame-to-frame pdc difference std 2.0 counts, i.e. ~1.4 counts of noise; at rest ~0.7).
    pdc = pdc + rng.normal(0, 0.7, T) + rng.normal(0, 1.2, T) * sliding
    ele = ele + rng.normal(0, 1.0, ele.shape)

    if style == "raw":
        b = rng.uniform(1800, 2300)
        pdc_o = b + pdc
        tdc_o = rng.uniform(2000, 2600) + tdc
        tac_o = rng.uniform(1900, 2100) + tac
        pac_o = rng.uniform(1900, 2100) + pac
        ele_o = rng.uniform(2800, 3400, size=(1, ele.shape[1])) - ele
    else:
        # Upstream-style: baseline-subtracted and clipped at 0, small positive offsets.
        pdc_o = np.clip(pdc + rng.uniform(0, 3), 0, None)
        tdc_o = np.clip(tdc + rng.uniform(0, 8), 0, None)
        tac_o = np.clip(tac + rng.uniform(0, 40), 0, None)
        pac_o = np.clip(pac + rng.uniform(10, 150), 0, None)
        ele_o = np.clip(ele + rng.uniform(0, 4, size=(1, ele.shape[1])), 0, None)
    r = lambda x: np.round(x)  # noqa: E731 - the sensor delivers integer counts
    labels = np.where(force < CONTACT_FORCE_N, 0, np.where(speed >= SLIP_SPEED, 2, 1))
    return Sequence(material, style, 1.6e9 + rng.uniform(0, 1e6) + t, r(tdc_o), r(tac_o), r(pdc_o),
                    r(pac_o), r(ele_o), labels.astype(np.int64), force, speed)


def generate_set(seed: int, count: int, layout: np.ndarray | None = None) -> list[Sequence]:
    """`count` sequences, materials balanced, styles half raw, half pretared."""
    layout = load_layout() if layout is None else layout
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        material = MATERIALS[i % 4]
        style = "raw" if (i // 4) % 2 == 0 else "pretared"
        out.append(generate(rng, material, style, layout))
    return out


# ---------------------------------------------------------------------------------------------
# Preprocessing exactly as graspd (service/core/src/tactile: taring.rs, detector.rs,
# stabilizer.rs FingerState::step). Tested from Rust with a fixture (tests/tactile_model.rs).


def pac_vibration(pac: np.ndarray) -> np.ndarray:
    """detector.rs pac_vibration for >= 3 samples per frame: RMS of second differences / sqrt 6."""
    d2 = pac[:, 2:] - 2 * pac[:, 1:-1] + pac[:, :-2]
    return np.sqrt((d2 ** 2).sum(axis=1) / (pac.shape[1] - 2) / 6.0)


def detector_samples(seq_tdc, seq_tac, seq_pdc, seq_pac, seq_ele, style: str):
    """Per frame: (ready, features[24]) as the stabilizer builds `DetectorSample`s.

    raw: TareConfig::default() (mean of the first 50 frames, electrodes falling); frames are
    used once the baseline is complete. pretared: TareConfig::pretared() (no baseline, rising).
    """
    T = len(seq_pdc)
    if style == "raw":
        n = BASELINE_FRAMES
        chans = np.concatenate([seq_pdc[:, None], seq_tdc[:, None], seq_tac[:, None], seq_ele], 1)
        base = chans[:n].sum(axis=0) / n
        sign = -1.0
        ready = np.arange(T) >= n
    else:
        base = np.zeros(3 + seq_ele.shape[1])
        sign = 1.0
        ready = np.ones(T, dtype=bool)
    feats = np.empty((T, 5 + seq_ele.shape[1]))
    feats[:, 0] = seq_pdc - base[0]
    feats[:, 1] = seq_pac.sum(axis=1) / seq_pac.shape[1]
    feats[:, 2] = pac_vibration(seq_pac)
    feats[:, 3] = seq_tdc - base[1]
    feats[:, 4] = seq_tac - base[2]
    feats[:, 5:] = sign * (seq_ele - base[3:][None, :])
    return ready, feats


def windows_for(feats: np.ndarray, ready: np.ndarray, window: int = WINDOW, stride: int = STRIDE,
                dtype=np.float32):
    """The windows the stabilizer hands its detector: for each kept frame (every k-th ready
    frame) the last <= l kept samples, left-padded to l by repeating the oldest (as
    LstmDetector does). Returns (frame indices, windows [N, l, F])."""
    idx = np.flatnonzero(ready)[::stride]
    kept = feats[idx]
    out = np.empty((len(idx), window, feats.shape[1]), dtype=dtype)
    for j in range(len(idx)):
        lo = max(0, j - window + 1)
        w = kept[lo : j + 1]
        if len(w) < window:
            w = np.concatenate([np.repeat(w[:1], window - len(w), axis=0), w])
        out[j] = w
    return idx, out


# ---------------------------------------------------------------------------------------------
# CSV I/O: the recordings' `_bio.csv` format and a labels file (MODEL_CARD.md, "Your own data").


def write_bio_csv(path: str, s: Sequence) -> None:
    header = ["timestamp", "tdc", "tac", "pdc"] + [f"pac{i}" for i in range(1, PAC_PER_FRAME + 1)]
    header += [f"ele{i}" for i in range(1, s.electrodes.shape[1] + 1)]
    with open(path, "w", newline="") as f:
        f.write(",".join(header) + "\n")
        for i in range(len(s.pdc)):
            vals = [f"{s.timestamp[i]:.3f}", *(f"{v:.0f}" for v in (s.tdc[i], s.tac[i], s.pdc[i]))]
            vals += [f"{v:.0f}" for v in s.pac[i]] + [f"{v:.0f}" for v in s.electrodes[i]]
            f.write(",".join(vals) + "\n")


def write_labels_csv(path: str, s: Sequence) -> None:
    with open(path, "w", newline="") as f:
        f.write("timestamp,event,material\n")
        for i in range(len(s.pdc)):
            f.write(f"{s.timestamp[i]:.3f},{EVENTS[s.labels[i]]},{s.material}\n")


def read_bio_csv(path: str):
    """Reads a `_bio.csv` (trailing commas allowed; columns by name like recording.rs)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names = [n.strip() for n in rows[0] if n.strip()]
    data = []
    for r in rows[1:]:
        if not r or all(not x.strip() for x in r):
            continue
        if len(r) == len(names) + 1 and r[-1].strip() == "":
            r = r[:-1]
        data.append([float(x) for x in r])
    a = np.array(data, dtype=np.float64)
    col = {n.lower(): i for i, n in enumerate(names)}
    pac = [col[f"pac{k}"] for k in range(1, 100) if f"pac{k}" in col] or [col["pac"]]
    ele = [col[f"ele{k}"] for k in range(1, 100) if f"ele{k}" in col]
    return dict(timestamp=a[:, col["timestamp"]], tdc=a[:, col["tdc"]], tac=a[:, col["tac"]],
                pdc=a[:, col["pdc"]], pac=a[:, pac], electrodes=a[:, ele])


def read_labels_csv(path: str):
    """`timestamp,event,material` per frame (event: non_contact|contact|slip)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    events = np.array([EVENTS.index(r["event"].strip()) for r in rows])
    materials = [r["material"].strip() for r in rows]
    return events, materials

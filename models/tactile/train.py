"""Trains the tactile detector of method.md section 5 (dissertation ch. 6.3) and exports it to
ONNX for graspd: an LSTM encoder-decoder over the window t_seq (reconstruction loss, Eq 6.2)
whose latent code feeds a contact-event classifier (non-contact / contact / slip, Eq 6.3) and a
material classifier (paper / foam / plastic / metal, Eq 6.4).

    python train.py                       # generated data (biotac_sim.py), seed 1
    python train.py --data DIR --tare raw # your own recordings (MODEL_CARD.md, "Your own data")

Writes tactile_detector.onnx, metrics.json and the Rust test fixture next to this file. The
ONNX output is checked against PyTorch (max |difference| <= 1e-4) before anything is written.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import time

import numpy as np
import torch
from torch import nn

import biotac_sim as sim

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
FIXTURE_DIR = os.path.join(REPO, "service", "core", "tests", "fixtures", "tactile_model")


class TactileDetector(nn.Module):
    """Encoder LSTM -> latent z -> (decoder LSTM reconstructing the window, event head,
    material head). Input: normalised window [B, l, F]; channel `pac` is centred over the
    window inside the model (its level is an AC-coupled offset that differs between drivers)."""

    def __init__(self, features: int, hidden: int, latent: int, pac_channel: int, dropout: float = 0.0):
        super().__init__()
        self.dropout = nn.Dropout(dropout)
        self.pac_channel = pac_channel
        self.encoder = nn.LSTM(features, hidden, batch_first=True)
        self.to_latent = nn.Linear(hidden, latent)
        self.decoder = nn.LSTM(latent, hidden, batch_first=True)
        self.reconstruct = nn.Linear(hidden, features)
        self.event = nn.Sequential(nn.Linear(latent, 32), nn.ReLU(), nn.Linear(32, 3))
        self.material = nn.Sequential(nn.Linear(latent, 32), nn.ReLU(), nn.Linear(32, 4))

    def prepare(self, x: torch.Tensor) -> torch.Tensor:
        p = self.pac_channel
        pac = x[:, :, p : p + 1] - x[:, :, p : p + 1].mean(dim=1, keepdim=True)
        return torch.cat([x[:, :, :p], pac, x[:, :, p + 1 :]], dim=2)

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        _, (h, _) = self.encoder(x)
        return torch.tanh(self.to_latent(h[-1]))

    def forward(self, x: torch.Tensor):
        x = self.prepare(x)
        z = self.encode(x)
        dec, _ = self.decoder(z[:, None, :].expand(-1, x.shape[1], -1))
        zd = self.dropout(z)
        return self.event(zd), self.material(zd), self.reconstruct(dec), x


class ExportHead(nn.Module):
    """What graspd runs: window -> (event logits [1, 3], material logits [1, 4])."""

    def __init__(self, net: TactileDetector):
        super().__init__()
        self.net = net

    def forward(self, window: torch.Tensor):
        z = self.net.encode(self.net.prepare(window))
        return self.net.event(z), self.net.material(z)


def windows_of(seqs, subsample: int = 1, rng=None):
    """Windows, event labels (newest frame), material labels and the sequence each came from;
    with `subsample` > 1 every subsample-th window from a random offset (more sequences for the
    same number of windows: less overfitting to one sequence's sensor and material draw)."""
    xs, ev, mat, sid = [], [], [], []
    for k, s in enumerate(seqs):
        ready, feats = sim.detector_samples(s.tdc, s.tac, s.pdc, s.pac, s.electrodes, s.style)
        idx, w = sim.windows_for(feats, ready)
        if subsample > 1:
            keep = slice(int(rng.integers(subsample)), None, subsample)
            idx, w = idx[keep], w[keep]
        xs.append(w)
        ev.append(s.labels[idx])
        mat.append(np.full(len(idx), sim.MATERIALS.index(s.material) if s.material in sim.MATERIALS else -1))
        sid.append(np.full(len(idx), k))
    return np.concatenate(xs), np.concatenate(ev), np.concatenate(mat), np.concatenate(sid)


def load_own(data: str, tare: str):
    """Your own recordings: DIR/<name>_bio.csv with DIR/<name>_labels.csv (MODEL_CARD.md)."""
    seqs = []
    for bio in sorted(glob.glob(os.path.join(data, "**", "*_bio.csv"), recursive=True)):
        lab = bio[: -len("_bio.csv")] + "_labels.csv"
        if not os.path.exists(lab):
            raise SystemExit(f"{bio}: no labels file {lab}")
        b = sim.read_bio_csv(bio)
        events, materials = sim.read_labels_csv(lab)
        if len(events) != len(b["pdc"]):
            raise SystemExit(f"{lab}: {len(events)} labels for {len(b['pdc'])} frames")
        known = [m for m in materials if m in sim.MATERIALS]
        if not known:
            raise SystemExit(f"{lab}: no frame names a material of {sim.MATERIALS}")
        material = max(set(known), key=known.count)
        seqs.append(sim.Sequence(material, tare, b["timestamp"], b["tdc"], b["tac"], b["pdc"], b["pac"],
                                 b["electrodes"], events, np.zeros(len(events)), np.zeros(len(events))))
    if not seqs:
        raise SystemExit(f"no *_bio.csv files under {data}")
    return seqs


def metrics(event_logits, material_logits, ev, mat):
    pe = event_logits.argmax(1)
    pm = material_logits.argmax(1)
    conf = np.zeros((3, 3), dtype=int)
    np.add.at(conf, (ev, pe), 1)
    contact = ev > 0
    mconf = np.zeros((4, 4), dtype=int)
    np.add.at(mconf, (mat[contact], pm[contact]), 1)
    return {
        "windows": int(len(ev)),
        "event_accuracy": float((pe == ev).mean()),
        "contact_accuracy": float(((pe > 0) == contact).mean()),
        "slip_accuracy": float(((pe == 2) == (ev == 2)).mean()),
        "material_accuracy_in_contact": float((pm[contact] == mat[contact]).mean()) if contact.any() else None,
        "event_confusion": conf.tolist(),
        "material_confusion": mconf.tolist(),
    }


def predict(net, x, batch=2048):
    net.eval()
    out_e, out_m = [], []
    with torch.no_grad():
        for i in range(0, len(x), batch):
            e, m, _, _ = net(torch.from_numpy(x[i : i + batch]))
            out_e.append(e.numpy())
            out_m.append(m.numpy())
    return np.concatenate(out_e), np.concatenate(out_m)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--train-sequences", type=int, default=1000)
    ap.add_argument("--test-sequences", type=int, default=400)
    ap.add_argument("--epochs", type=int, default=6)
    ap.add_argument("--hidden", type=int, default=64)
    ap.add_argument("--latent", type=int, default=64)
    ap.add_argument("--batch", type=int, default=128)
    ap.add_argument("--subsample", type=int, default=1, help="keep every n-th training window")
    ap.add_argument("--dropout", type=float, default=0.0, help="dropout on the latent code")
    ap.add_argument("--data", help="train on your own recordings in DIR instead of generated data")
    ap.add_argument("--tare", choices=["raw", "pretared"], default="raw",
                    help="how graspd will tare your recordings (TareConfig::default() or pretared())")
    ap.add_argument("--out", default=os.path.join(HERE, "tactile_detector.onnx"))
    ap.add_argument("--no-fixture", action="store_true", help="do not rewrite the Rust test fixture")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--fixture-only", action="store_true",
                    help="only rewrite the Rust test fixture from the existing --out model")
    args = ap.parse_args()
    if args.fixture_only:
        import onnxruntime as ort

        sess = ort.InferenceSession(args.out, providers=["CPUExecutionProvider"])
        meta = sess.get_modelmeta().custom_metadata_map
        mean = np.array([float(v) for v in meta["graspd.tactile.mean"].split(",")])
        std = np.array([float(v) for v in meta["graspd.tactile.std"].split(",")])
        write_fixture(sim.generate_set(args.seed + 1000, args.test_sequences), sess, mean, std)
        return
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    started = time.time()

    if args.data:
        seqs = load_own(args.data, args.tare)
        order = rng.permutation(len(seqs))
        n_test = max(1, len(seqs) // 5)
        test_seqs = [seqs[i] for i in order[:n_test]]
        train_seqs = [seqs[i] for i in order[n_test:]]
        source = f"own recordings in {args.data} (tare {args.tare}); {len(test_seqs)} held out"
    else:
        train_seqs = sim.generate_set(args.seed, args.train_sequences)
        # Held-out generated data: a different seed, so different sequences and sensors.
        test_seqs = sim.generate_set(args.seed + 1000, args.test_sequences)
        source = f"biotac_sim.generate_set(seed={args.seed}, {args.train_sequences}) train, seed {args.seed + 1000} test"
    x, ev, mat, _ = windows_of(train_seqs, args.subsample, rng)
    xt, evt, matt, sidt = windows_of(test_seqs)
    print(f"{len(x)} training windows, {len(xt)} test windows ({time.time() - started:.0f} s)", flush=True)

    flat = x.reshape(-1, x.shape[2]).astype(np.float64)
    mean = flat.mean(axis=0)
    std = np.maximum(flat.std(axis=0), 1e-3)
    norm = lambda a: ((a - mean) / std).astype(np.float32)  # noqa: E731
    xn, xtn = norm(x), norm(xt)

    net = TactileDetector(x.shape[2], args.hidden, args.latent, sim.FEATURES.index("pac"), args.dropout)
    opt = torch.optim.Adam(net.parameters(), lr=2e-3)
    steps = args.epochs * (len(xn) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=3e-3, total_steps=steps)
    ce = nn.CrossEntropyLoss()
    xs, evs, mats = torch.from_numpy(xn), torch.from_numpy(ev), torch.from_numpy(mat)
    for epoch in range(args.epochs):
        net.train()
        perm = torch.from_numpy(rng.permutation(len(xn)))
        tot = [0.0, 0.0, 0.0]
        nb = len(xn) // args.batch
        for b in range(nb):
            i = perm[b * args.batch : (b + 1) * args.batch]
            e, m, rec, target = net(xs[i])
            l_rec = ((rec - target) ** 2).mean()  # Eq 6.2
            l_ev = ce(e, evs[i])  # Eq 6.3
            mask = (evs[i] > 0) & (mats[i] >= 0)
            l_mat = ce(m[mask], mats[i][mask]) if mask.any() else torch.zeros(())  # Eq 6.4, in contact
            loss = l_rec + l_ev + l_mat
            opt.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(net.parameters(), 1.0)
            opt.step()
            sched.step()
            for k, v in enumerate((l_rec, l_ev, l_mat)):
                tot[k] += float(v.detach())
        pe, pm = predict(net, xtn)
        mt = metrics(pe, pm, evt, matt)
        print(f"epoch {epoch + 1}: rec {tot[0] / nb:.3f} event {tot[1] / nb:.3f} material {tot[2] / nb:.3f} | "
              f"test event {mt['event_accuracy']:.3f} contact {mt['contact_accuracy']:.3f} "
              f"slip {mt['slip_accuracy']:.3f} material {mt['material_accuracy_in_contact']:.3f} "
              f"({time.time() - started:.0f} s)", flush=True)
    train_time = time.time() - started

    # Export and verify.
    import onnx
    import onnxruntime as ort

    head = ExportHead(net).eval()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    dummy = torch.from_numpy(xtn[:1])
    # A dynamic batch axis: graspd runs the windows of sessions due together in one run.
    batch = {0: "batch"}
    torch.onnx.export(head, (dummy,), args.out, input_names=["window"],
                      output_names=["event_logits", "material_logits"], opset_version=17, dynamo=False,
                      dynamic_axes={"window": batch, "event_logits": batch, "material_logits": batch})
    model = onnx.load(args.out)
    meta = {
        "graspd.tactile.features": ",".join(sim.FEATURES),
        "graspd.tactile.mean": ",".join(f"{v:.9g}" for v in mean),
        "graspd.tactile.std": ",".join(f"{v:.9g}" for v in std),
        "graspd.tactile.window": str(sim.WINDOW),
        "graspd.tactile.stride": str(sim.STRIDE),
        "graspd.tactile.padding": "repeat_oldest",
        "graspd.tactile.events": ",".join(sim.EVENTS),
        "graspd.tactile.materials": ",".join(sim.MATERIALS),
        "graspd.tactile.training": source,
    }
    del model.metadata_props[:]
    for k, v in meta.items():
        p = model.metadata_props.add()
        p.key, p.value = k, v
    model.producer_name = "graspd models/tactile/train.py"
    onnx.checker.check_model(model)
    onnx.save(model, args.out)
    sess = ort.InferenceSession(args.out, providers=["CPUExecutionProvider"])
    worst = 0.0
    with torch.no_grad():
        for i in rng.choice(len(xtn), size=min(300, len(xtn)), replace=False):
            w = xtn[i : i + 1]
            te, tm = head(torch.from_numpy(w))
            oe, om = sess.run(None, {"window": w})
            worst = max(worst, float(np.abs(te.numpy() - oe).max()), float(np.abs(tm.numpy() - om).max()))
    print(f"ONNX vs PyTorch: max |difference| {worst:.2e} over 300 windows")
    if worst > 1e-4:
        raise SystemExit(f"ONNX output differs from PyTorch by {worst:.2e} > 1e-4")

    pe, pm = predict(net, xtn)
    result = {
        "source": source,
        "train_windows": int(len(x)),
        "test": metrics(pe, pm, evt, matt),
        "test_by_style": {},
        "train_seconds": round(train_time, 1),
        "onnx_bytes": os.path.getsize(args.out),
        "onnx_vs_pytorch_max_abs": worst,
        "hidden": args.hidden,
        "latent": args.latent,
        "epochs": args.epochs,
        "parameters": int(sum(p.numel() for p in head.parameters())),
    }
    styles = np.array([test_seqs[k].style for k in sidt])
    for style in ("raw", "pretared"):
        m = styles == style
        if m.any():
            result["test_by_style"][style] = metrics(pe[m], pm[m], evt[m], matt[m])
    out_metrics = os.path.join(os.path.dirname(args.out), "metrics.json")
    with open(out_metrics, "w") as f:
        json.dump(result, f, indent=1)
    print(json.dumps({k: v for k, v in result["test"].items() if "confusion" not in k}, indent=1))
    if not args.data and not args.no_fixture:
        write_fixture(test_seqs, sess, mean, std)


def write_fixture(test_seqs, sess, mean, std):
    """A few held-out generated sequences in the `_bio.csv` + labels format for the Rust tests,
    and, for the first, the windows graspd must build and the ONNX probabilities."""
    os.makedirs(FIXTURE_DIR, exist_ok=True)
    for old in glob.glob(os.path.join(FIXTURE_DIR, "*.csv")):
        os.remove(old)
    # One per material, raw and pretared alternating, trimmed to 3 s (with all three events) to
    # stay small.
    n = 300
    chosen = []
    for k, mat in enumerate(sim.MATERIALS):
        style = ("raw", "pretared")[k % 2]
        chosen.append(next(s for s in test_seqs if s.material == mat and s.style == style
                           and len(s.pdc) >= n and set(s.labels[sim.BASELINE_FRAMES:n]) == {0, 1, 2}))
    names = []
    for k, s in enumerate(chosen):
        cut = sim.Sequence(s.material, s.style, s.timestamp[:n], s.tdc[:n], s.tac[:n], s.pdc[:n],
                           s.pac[:n], s.electrodes[:n], s.labels[:n], s.force[:n], s.speed[:n])
        name = f"gen{k}_{s.material}_{s.style}"
        sim.write_bio_csv(os.path.join(FIXTURE_DIR, name + "_bio.csv"), cut)
        sim.write_labels_csv(os.path.join(FIXTURE_DIR, name + "_labels.csv"), cut)
        names.append((name, s.style))
        if k == 0:
            ready, feats = sim.detector_samples(cut.tdc, cut.tac, cut.pdc, cut.pac, cut.electrodes, cut.style)
            idx, w = sim.windows_for(feats, ready, dtype=np.float64)
            picks = [0, 5, 31, len(idx) - 1]
            probe = []
            for j in picks:
                wn = ((w[j : j + 1] - mean) / std).astype(np.float32)
                oe, om = sess.run(None, {"window": wn})
                sm = lambda a: (np.exp(a - a.max()) / np.exp(a - a.max()).sum()).tolist()  # noqa: E731
                # The stabilizer's window is only as long as the kept samples so far.
                n_kept = min(j + 1, sim.WINDOW)
                probe.append({"frame": int(idx[j]), "window": w[j, sim.WINDOW - n_kept :].tolist(),
                              "event_probabilities": sm(oe[0]), "material_probabilities": sm(om[0])})
            with open(os.path.join(FIXTURE_DIR, "probe.json"), "w") as f:
                json.dump({"sequence": name, "style": s.style, "windows": probe}, f)
    with open(os.path.join(FIXTURE_DIR, "README.md"), "w") as f:
        f.write("# Generated tactile fixture\n\nWritten by `models/tactile/train.py` from held-out generated "
                "sequences (biotac_sim.py; no real recordings). `<name>_bio.csv` in the dexrob `_bio.csv` "
                "format, `<name>_labels.csv` `timestamp,event,material` per frame; the style (raw: tare "
                "with the first 50 frames, electrodes falling; pretared: no taring) is in the name. "
                "`probe.json`: the windows graspd must hand its detector for frames of the first "
                "sequence and the ONNX probabilities for them.\n\nSequences: "
                + ", ".join(n for n, _ in names) + "\n")


if __name__ == "__main__":
    main()

"""Makes the batch axis of an exported tactile detector dynamic (models/tactile/MODEL_CARD.md).

graspd runs the windows of several sessions that are due together in one run of the model when
its input and outputs have a dynamic batch axis (issue 16 part 4). train.py exports it that way;
this script gives an older export the same signature without retraining: only the declared shape
of the input `window` and of the two outputs changes (`batch` instead of 1), the graph and its
weights stay as they are (its LSTM takes the batch size from the input's shape). It then checks
with ONNX Runtime that a batch of windows gives what each window gives alone, to 1e-5.

    .tools/models-venv/bin/python models/tactile/batch_axis.py models/tactile/tactile_detector.onnx
"""

import sys

import numpy as np
import onnx
import onnxruntime as ort


def main(path: str) -> None:
    model = onnx.load(path)
    graph = model.graph
    for value in [graph.input[0], *graph.output]:
        value.type.tensor_type.shape.dim[0].dim_param = "batch"
    onnx.checker.check_model(model)
    onnx.save(model, path)
    sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    shape = [d.dim_value for d in graph.input[0].type.tensor_type.shape.dim[1:]]
    windows = np.random.default_rng(0).normal(size=(17, *shape)).astype(np.float32)
    together = sess.run(None, {"window": windows})
    worst = 0.0
    for i in range(len(windows)):
        alone = sess.run(None, {"window": windows[i : i + 1]})
        for a, b in zip(alone, together):
            worst = max(worst, float(np.abs(a[0] - b[i]).max()))
    print(f"{path}: batch axis dynamic; a batch of 17 against each window alone: max |difference| {worst:.2e}")
    if worst > 1e-5:
        raise SystemExit(f"batched outputs differ by {worst:.2e} > 1e-5")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "models/tactile/tactile_detector.onnx")

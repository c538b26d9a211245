"""ReconROS's classifier service: a numpy CNN behind a ROS service, queried by a client node."""

import numpy as np
from cnn import classify, load
from train import split

from hetros import Node
from hetros.interfaces.classifier_msgs.srv import Classify


def classifier(node: Node) -> None:
    params = load()

    def answer(request: Classify.Request) -> Classify.Response:
        scores = classify(params, np.asarray(request.pixels))
        return Classify.Response(digit=int(scores.argmax()), scores=scores.astype(np.float32))

    node.create_service(Classify, "/classify", answer)


def client(node: Node) -> None:
    """Sends every held-out digit (the split train.py kept out) and reports the accuracy."""
    _train_x, test_x, _train_y, test_y = split()
    service = node.create_client(Classify, "/classify")
    correct = 0
    for image, label in zip(test_x, test_y, strict=True):
        response = service.call(Classify.Request(pixels=image.reshape(64).astype(np.uint8)), timeout=10.0)
        correct += int(response.digit == label)
    node.log.info("accuracy %.4f on %d held-out digits (%d correct)", correct / len(test_y), len(test_y), correct)

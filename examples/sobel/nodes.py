"""ReconROS's Sobel example (Listings 1-3, Fig. 5): camera -> DIP -> sobel_service -> display.

The DIP node subscribes to /image_raw, calls the ``/sobel_service`` service (a custom
.srv of this example's own message package) served by the Sobel node, and publishes
/image_filtered. Sobel: two 3x3 kernels per channel, magnitude approximated as
|Gx| + |Gy| and clipped to 255, border pixels 0; vectorised with numpy slices.
"""

import numpy as np

from hetros import Node
from hetros.interfaces.application_msgs.srv import SobelSrv
from hetros.interfaces.sensor_msgs.msg import Image

HEIGHT, WIDTH = 480, 640


def frame(seq: int) -> np.ndarray:
    """A deterministic 640x480 RGB test scene: gradients, a bright box, stripes, noise."""
    rng = np.random.default_rng(seq)
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    img = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    img[..., 0] = (x * 255 // WIDTH).astype(np.uint8)
    img[..., 1] = (y * 255 // HEIGHT).astype(np.uint8)
    img[..., 2] = np.where((x // (8 + seq % 8)) % 2 == 0, 200, 30).astype(np.uint8)
    top, left = 100 + 10 * seq, 200 + 7 * seq
    img[top:top + 120, left:left + 160] = 255
    noise = rng.integers(0, 20, img.shape, dtype=np.uint8)
    noisy: np.ndarray = np.clip(img.astype(np.int16) + noise, 0, 255).astype(np.uint8)
    return noisy


def sobel(img: np.ndarray) -> np.ndarray:
    """|Gx| + |Gy| per channel with the 3x3 Sobel kernels, clipped to 255."""
    x = img.astype(np.int32)
    gx = (x[:-2, 2:] + 2 * x[1:-1, 2:] + x[2:, 2:]) - (x[:-2, :-2] + 2 * x[1:-1, :-2] + x[2:, :-2])
    gy = (x[2:, :-2] + 2 * x[2:, 1:-1] + x[2:, 2:]) - (x[:-2, :-2] + 2 * x[:-2, 1:-1] + x[:-2, 2:])
    out = np.zeros_like(img)
    out[1:-1, 1:-1] = np.clip(np.abs(gx) + np.abs(gy), 0, 255)
    return out


def image_message(pixels: np.ndarray, seq: int) -> Image:
    msg = Image(height=pixels.shape[0], width=pixels.shape[1], encoding="rgb8", step=pixels.shape[1] * 3,
                data=pixels.reshape(-1))
    msg.header.frame_id = f"frame{seq}"
    return msg


def pixels_of(msg: Image) -> np.ndarray:
    return msg.data.reshape(msg.height, msg.width, 3)


def camera(node: Node) -> None:
    pub = node.create_publisher(Image, "/image_raw")
    for seq in node.rate(node.get_parameter("hz", 10.0)):
        if seq >= node.get_parameter("frames", 10):
            return
        pub.publish(image_message(frame(seq), seq))


def dip(node: Node) -> None:
    sobel_service = node.create_client(SobelSrv, "/sobel_service")
    pub = node.create_publisher(Image, "/image_filtered")

    def on_image(msg: Image) -> None:
        response = sobel_service.call(SobelSrv.Request(image=msg), timeout=10.0)
        pub.publish(response.image)

    node.create_subscription(Image, "/image_raw", on_image)


def sobel_node(node: Node) -> None:
    def filter_image(request: SobelSrv.Request) -> SobelSrv.Response:
        filtered = image_message(sobel(pixels_of(request.image)), 0)
        filtered.header = request.image.header
        return SobelSrv.Response(image=filtered)

    node.create_service(SobelSrv, "/sobel_service", filter_image)


def display(node: Node) -> None:
    sub = node.create_subscription(Image, "/image_filtered")
    for _ in range(node.get_parameter("frames", 10)):
        msg = sub.take(timeout=30.0)
        seq = int(msg.header.frame_id.removeprefix("frame"))
        if not np.array_equal(pixels_of(msg), sobel(frame(seq))):
            raise ValueError(f"filtered frame {seq} differs from the Sobel of frame {seq}")
        node.log.info("frame %d filtered correctly (%d edge pixels)", seq, int((pixels_of(msg) > 128).sum()))

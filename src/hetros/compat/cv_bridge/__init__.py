"""cv_bridge for rclpy and rospy nodes: sensor_msgs Images as numpy arrays and back.

``imgmsg_to_cv2`` of an image in its own encoding is a view of the message's bytes, no copy (rows
padded past their pixels, ``step``, are skipped by the view's strides); a received image's view is
read-only, as its message is. Conversions between mono, rgb, bgr, rgba and bgra at 8 and 16 bits are
done in numpy with OpenCV's arithmetic (its fixed-point grey weights, its rounding between depths), so
they give the bytes Debian's cv_bridge gives; Bayer and YUV conversions and compressed images need
OpenCV (``pip install opencv-python-headless``), used when it is installed."""

from __future__ import annotations

import re
import sys
from typing import Any

import numpy as np

from ..._errors import Error
from ...msg import registry


class CvBridgeError(Error, TypeError):
    """An image, an encoding or a conversion cv_bridge cannot handle."""


_DTYPES = {"8U": "uint8", "8S": "int8", "16U": "uint16", "16S": "int16", "32S": "int32", "32F": "float32",
           "64F": "float64"}
_CV_DEPTH = {np.dtype(v).name: k for k, v in _DTYPES.items()}
# sensor_msgs/image_encodings' named encodings: (depth, channels)
_NAMED = {"mono8": ("8U", 1), "mono16": ("16U", 1), "rgb8": ("8U", 3), "bgr8": ("8U", 3), "rgba8": ("8U", 4),
          "bgra8": ("8U", 4), "rgb16": ("16U", 3), "bgr16": ("16U", 3), "rgba16": ("16U", 4),
          "bgra16": ("16U", 4), "yuv422": ("8U", 2), "yuv422_yuy2": ("8U", 2), "uyvy": ("8U", 2),
          "yuyv": ("8U", 2), "nv21": ("8U", 2), "nv24": ("8U", 2)}
for _pattern in ("rggb", "bggr", "gbrg", "grbg"):
    _NAMED[f"bayer_{_pattern}8"] = ("8U", 1)
    _NAMED[f"bayer_{_pattern}16"] = ("16U", 1)
_GENERIC = re.compile(r"^(8U|8S|16U|16S|32S|32F|64F)(?:C(\d+))?$")
# the colour orders numpy converts between: channel letters of each
_ORDERS = {"mono": "y", "rgb": "rgb", "bgr": "bgr", "rgba": "rgba", "bgra": "bgra"}


def encoding_layout(encoding: str) -> tuple[np.dtype[Any], int]:
    """(dtype, channels) of an encoding: a named one (``rgb8``) or OpenCV's (``32FC3``, ``8UC1``)."""
    named = _NAMED.get(encoding)
    if named is not None:
        return np.dtype(_DTYPES[named[0]]), named[1]
    generic = _GENERIC.match(encoding)
    if generic is None:
        raise CvBridgeError(f"Unrecognized image encoding [{encoding}]: give one of sensor_msgs/image_encodings' "
                            "(mono8, rgb8, bgra16, bayer_rggb8, yuv422, ...) or OpenCV's (8UC3, 32FC1, ...)")
    return np.dtype(_DTYPES[generic.group(1)]), int(generic.group(2) or 1)


def _colour(encoding: str) -> tuple[str, int] | None:
    """(channel order, bits) of a colour encoding numpy converts (mono/rgb/bgr/rgba/bgra at 8 or 16)."""
    found = re.fullmatch(r"(mono|rgba|bgra|rgb|bgr)(8|16)", encoding)
    return None if found is None else (_ORDERS[found.group(1)], int(found.group(2)))


def _grey(image: np.ndarray, order: str, bits: int) -> np.ndarray:
    """OpenCV's RGB-to-grey in its fixed point: 14 fractional bits at 8 bits, 15 at 16 (OpenCV's own where it
    is installed: the same bytes, about 30 times sooner than numpy's passes over the image)."""
    cv2 = _installed_opencv()
    if cv2 is not None:
        code = {"rgb": "COLOR_RGB2GRAY", "bgr": "COLOR_BGR2GRAY", "rgba": "COLOR_RGBA2GRAY",
                "bgra": "COLOR_BGRA2GRAY"}[order]
        grey: np.ndarray = cv2.cvtColor(np.ascontiguousarray(image), getattr(cv2, code))
        return grey
    weights = {"r": 4899, "g": 9617, "b": 1868} if bits == 8 else {"r": 9798, "g": 19235, "b": 3735}
    shift = 14 if bits == 8 else 15
    # in place, in 32 bits: the weights sum to 1 << shift, so 65535 of each stays below 2**32
    total = image[..., order.index("r")].astype(np.uint32)
    total *= weights["r"]
    for c in "gb":
        channel = image[..., order.index(c)].astype(np.uint32)
        channel *= weights[c]
        total += channel
    total += 1 << (shift - 1)
    total >>= shift
    return total.astype(image.dtype)


def _convert(image: np.ndarray, source: str, target: str) -> np.ndarray:
    src, dst = _colour(source), _colour(target)
    if src is None or dst is None:
        return _convert_with_opencv(image, source, target)
    (src_order, src_bits), (dst_order, dst_bits) = src, dst
    if src_order == "y" and dst_order != "y":
        image = np.repeat(image[..., None], 3, axis=2)
        src_order = "rgb"
    if dst_order == "y" and src_order != "y":
        image = _grey(image, src_order, src_bits)
    elif dst_order != "y":
        top = np.iinfo(image.dtype).max
        planes = [image[..., src_order.index(c)] if c in src_order else np.full(image.shape[:2], top, image.dtype)
                  for c in dst_order]
        image = np.stack(planes, axis=2)
    if src_bits != dst_bits:
        image = (np.rint(image.astype(np.float64) / 257.0).astype(np.uint8) if dst_bits == 8
                 else image.astype(np.uint16) * np.uint16(257))
    return np.ascontiguousarray(image)


def _convert_with_opencv(image: np.ndarray, source: str, target: str) -> np.ndarray:
    for name, encoding in (("source", source), ("target", target)):
        if encoding not in _NAMED:
            raise CvBridgeError(f"[{encoding}] is not a color format; the {name} of a conversion must be one "
                                "(passthrough keeps an image as it is)")
    cv2 = _installed_opencv()
    if cv2 is None:
        raise CvBridgeError(f"converting [{source}] to [{target}] needs OpenCV (pip install "
                            "opencv-python-headless); numpy converts mono/rgb/bgr/rgba/bgra at 8 and 16 bits")
    codes = {("yuv422", "rgb8"): "COLOR_YUV2RGB_UYVY", ("yuv422", "bgr8"): "COLOR_YUV2BGR_UYVY",
             ("yuv422_yuy2", "rgb8"): "COLOR_YUV2RGB_YUY2", ("yuv422_yuy2", "bgr8"): "COLOR_YUV2BGR_YUY2"}
    # OpenCV names a Bayer pattern by its second row's middle pair, so ROS's rggb is OpenCV's BG
    for pattern, cv_name in (("rggb", "BG"), ("bggr", "RG"), ("gbrg", "GR"), ("grbg", "GB")):
        for bits in ("8", "16"):
            codes[(f"bayer_{pattern}{bits}", f"bgr{bits}")] = f"COLOR_Bayer{cv_name}2BGR"
            codes[(f"bayer_{pattern}{bits}", f"rgb{bits}")] = f"COLOR_Bayer{cv_name}2RGB"
            codes[(f"bayer_{pattern}{bits}", f"mono{bits}")] = f"COLOR_Bayer{cv_name}2GRAY"
    code = codes.get((source, target))
    if code is None:
        raise CvBridgeError(f"Unsupported conversion from [{source}] to [{target}]")
    converted: np.ndarray = cv2.cvtColor(image, getattr(cv2, code))
    return converted


class CvBridge:
    """cv_bridge's CvBridge (ROS 1's and ROS 2's methods)."""

    def encoding_to_dtype_with_channels(self, encoding: str) -> tuple[str, int]:
        dtype, channels = encoding_layout(encoding)
        return dtype.name, channels

    def dtype_with_channels_to_cvtype2(self, dtype: Any, n_channels: int) -> str:
        return f"{_CV_DEPTH[np.dtype(dtype).name]}C{n_channels}"

    def imgmsg_to_cv2(self, img_msg: Any, desired_encoding: str = "passthrough") -> np.ndarray:
        dtype, channels = encoding_layout(img_msg.encoding)
        dtype = dtype.newbyteorder(">" if img_msg.is_bigendian else "<")
        height, width, step = int(img_msg.height), int(img_msg.width), int(img_msg.step)
        row = width * channels * dtype.itemsize
        step = step or row
        data = img_msg.data
        buffer = data if isinstance(data, np.ndarray | bytes | bytearray | memoryview) else bytes(data)
        size = len(buffer) if not isinstance(buffer, np.ndarray) else buffer.nbytes
        if step < row or size < step * (height - 1) + row:
            raise CvBridgeError(f"the image holds {size} bytes, too few for {height} rows of step {step} ({width} "
                                f"pixels of {channels} x {dtype.itemsize} bytes): a damaged or truncated message")
        shape = (height, width) if channels == 1 else (height, width, channels)
        strides = (step, channels * dtype.itemsize) if channels == 1 else \
            (step, channels * dtype.itemsize, dtype.itemsize)
        image = np.ndarray(shape, dtype=dtype, buffer=buffer, strides=strides)
        if img_msg.is_bigendian != (sys.byteorder == "big"):
            image = image.byteswap().view(image.dtype.newbyteorder())
        if desired_encoding in ("passthrough", img_msg.encoding):
            return image
        return _convert(image, img_msg.encoding, desired_encoding)

    def cv2_to_imgmsg(self, cvim: Any, encoding: str = "passthrough", header: Any = None) -> Any:
        if not isinstance(cvim, np.ndarray | np.generic):
            raise TypeError("Your input type is not a numpy array")
        image = np.asarray(cvim)
        if image.ndim not in (2, 3):
            raise CvBridgeError(f"an image must be a 2-D or 3-D array (rows, columns[, channels]), not of shape "
                                f"{image.shape}")
        if image.dtype.name not in _CV_DEPTH:
            raise CvBridgeError(f"an image's type must be one of {', '.join(_CV_DEPTH)}, not {image.dtype.name}")
        channels = 1 if image.ndim == 2 else image.shape[2]
        cv_type = self.dtype_with_channels_to_cvtype2(image.dtype, channels)
        if encoding != "passthrough":
            dtype, wanted = encoding_layout(encoding)
            if self.dtype_with_channels_to_cvtype2(dtype, wanted) != cv_type:
                raise CvBridgeError(f"encoding specified as {encoding}, but image has incompatible type {cv_type}")
        message = registry().get("sensor_msgs/msg/Image")()
        if header is not None:
            message.header = header
        message.height, message.width = image.shape[0], image.shape[1]
        message.encoding = cv_type if encoding == "passthrough" else encoding
        big = image.dtype.byteorder == ">" or (image.dtype.byteorder == "=" and sys.byteorder == "big")
        message.is_bigendian = int(big)
        message.step = image.shape[1] * channels * image.dtype.itemsize
        message.data = np.frombuffer(np.ascontiguousarray(image).tobytes(), dtype=np.uint8)
        return message

    def compressed_imgmsg_to_cv2(self, cmprs_img_msg: Any, desired_encoding: str = "passthrough") -> np.ndarray:
        cv2 = _opencv("compressed images")
        image: np.ndarray = cv2.imdecode(np.frombuffer(bytes(cmprs_img_msg.data), np.uint8), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise CvBridgeError(f"the compressed image ({cmprs_img_msg.format!r}, {len(cmprs_img_msg.data)} bytes) "
                                "does not decode")
        if desired_encoding == "passthrough":
            return image
        return _convert(image, "bgr8" if image.ndim == 3 else "mono8", desired_encoding)

    def cv2_to_compressed_imgmsg(self, cvim: Any, dst_format: str = "jpg") -> Any:
        cv2 = _opencv("compressed images")
        ok, encoded = cv2.imencode(f".{dst_format}", cvim)
        if not ok:
            raise CvBridgeError(f"OpenCV cannot encode this image as {dst_format}")
        message = registry().get("sensor_msgs/msg/CompressedImage")()
        message.format = dst_format
        message.data = np.asarray(encoded, dtype=np.uint8).reshape(-1)
        return message


def _installed_opencv() -> Any:
    """OpenCV's module where it is installed, else None."""
    try:
        import cv2  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return None
    return cv2


def _opencv(what: str) -> Any:
    cv2 = _installed_opencv()
    if cv2 is None:
        raise CvBridgeError(f"{what} need OpenCV: pip install opencv-python-headless")
    return cv2


def getCvType(encoding: str) -> int:
    """OpenCV's type number of an encoding (CV_8UC3 is 16)."""
    dtype, channels = encoding_layout(encoding)
    depth = list(_CV_DEPTH).index(dtype.name)
    return depth + ((channels - 1) << 3)


__all__ = ["CvBridge", "CvBridgeError", "encoding_layout", "getCvType"]

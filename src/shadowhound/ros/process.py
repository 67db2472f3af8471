"""Running one rclpy node as a process: the command line, signals, the executor, shutdown.

Shared by `shadowhound node` and `shadowhound sim-driver`. The executor spins on its own thread
so the main thread stays free for SIGINT/SIGTERM, which stop the node cleanly (exit 0).
"""

from __future__ import annotations

import logging
import signal
import sys
import threading
from collections.abc import Callable, Sequence

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from ..errors import ConfigError
from ..exit_codes import EXIT_OK, EXIT_USAGE
from ..serving import settle_heap


def run_node(
    prog: str,
    node_name: str,
    argv: Sequence[str] | None,
    usage: str,
    make: Callable[[], Node],
    close: Callable[[Node], None],
    goodbye: str,
    extra_nodes: Callable[[Node], Sequence[Node]] = lambda _node: (),
) -> int:
    """Start the node `make()` builds, spin until a signal, then `close` it and exit 0.

    Parameters come as `--ros-args -p NAME:=VALUE`; invalid ones (a ConfigError from `make`)
    exit 2 with the message. The package's `logging` goes to the node's ROS logger.
    `extra_nodes(node)` are spun by the same executor (the node destroys them itself).
    """
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        extra = remove_ros_args([node_name, *args])[1:]
    except Exception as exc:  # rcl reports malformed --ros-args this way
        print(f"{prog}: invalid ROS arguments: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if any(a in ("-h", "--help") for a in extra):
        print(usage)
        return EXIT_OK
    if extra:
        print(
            f"{prog}: unexpected arguments {extra}; give parameters as --ros-args -p "
            "NAME:=VALUE (see --help)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    stop = threading.Event()
    try:
        rclpy.init(args=[node_name, *args], signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # rclpy raises several types for a bad environment
        print(f"{prog}: cannot start ROS 2: {exc}", file=sys.stderr)
        return EXIT_USAGE
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    try:
        node = make()
    except ConfigError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        rclpy.try_shutdown()
        return EXIT_USAGE
    handler = _RosLogHandler(node)
    package_log = logging.getLogger("shadowhound")
    package_log.addHandler(handler)
    package_log.setLevel(logging.INFO)
    executor = SingleThreadedExecutor()  # callbacks are short; slow work runs on other threads
    for each in (node, *extra_nodes(node)):
        executor.add_node(each)
    settle_heap()  # a long-running node: keep full collections short (serving.py)
    spinner = threading.Thread(target=_spin, args=(executor, stop), name="ros-executor")
    spinner.start()
    try:
        while not stop.wait(0.5):  # the main thread stays free for the signal handlers
            pass
    except KeyboardInterrupt:
        pass
    finally:
        node.get_logger().info(goodbye)
        close(node)
        package_log.removeHandler(handler)
        executor.shutdown(timeout_sec=2.0)
        spinner.join(2.0)
        node.destroy_node()
        rclpy.try_shutdown()
    return EXIT_OK


def _spin(executor: SingleThreadedExecutor, stop: threading.Event) -> None:
    try:
        executor.spin()
    except ExternalShutdownException:
        pass  # shutting down: the main thread cleans up
    finally:
        stop.set()


class _RosLogHandler(logging.Handler):
    """Forwards the package's `logging` records to the node's ROS logger."""

    def __init__(self, node: Node) -> None:
        super().__init__()
        self._logger = node.get_logger()

    def emit(self, record: logging.LogRecord) -> None:
        text = f"{record.name}: {self.format(record)}"
        if record.levelno >= logging.ERROR:
            self._logger.error(text)
        elif record.levelno >= logging.WARNING:
            self._logger.warning(text)
        else:
            self._logger.info(text)

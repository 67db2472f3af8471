"""unitree_api and unitree_go as the project ships them (ros2/unitree_api: Request, Response and
their parts; ros2/unitree_go: SportModeState, LowState and their parts) are Unitree's own
(unitreerobotics/unitree_ros2, cyclonedds_ws/src/unitree/): the same type hashes, so the Go2
EDU's sport service and state publishers and the go2_edu robot match over DDS. A copy that
differed in one field name or type would get another hash and never connect.

How the expected hashes were computed: unitree_ros2's own definitions (branch master, commit
eea2719; cyclonedds_ws/src/unitree/unitree_api/msg/{Request, RequestHeader, RequestIdentity,
RequestLease, RequestPolicy, Response, ResponseHeader, ResponseStatus}.msg and
cyclonedds_ws/src/unitree/unitree_go/msg/{SportModeState, IMUState, TimeSpec, LowState,
BmsState, MotorState}.msg) run through rosidl's own generators with

    python scripts/type_hash.py unitree_api path/to/unitree_api/msg/*.msg    # those eight
    python scripts/type_hash.py unitree_go path/to/unitree_go/msg/*.msg      # those six

which prints the hashes below. (Upstream's repository carries no hashes of its own: its
workspace is built on the robot's side, and Jazzy's rosidl computes them the same way there.)

Skipped without rclpy or the packages unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "unitree_api", "unitree_go", "rosidl_generator_type_description")

from tests.ros.rosclient import ROOT, RosClient, wait_until  # noqa: E402
from tests.ros.type_hashes import computed, installed  # noqa: E402

UNITREE_API = {
    "unitree_api/msg/Request": "RIHS01_60dda80d19538b06c8f79b77222b1b7642dd753b8439a6bd535ff0cba08c5378",  # noqa: E501
    "unitree_api/msg/RequestHeader": "RIHS01_4273d5fbe6bee52502f55a6a73427e4ae2f12329f175d7c07b95341fd527acff",  # noqa: E501
    "unitree_api/msg/RequestIdentity": "RIHS01_912fcf308a7cd6e27ea3aeea02515f587fa666b76af1963660429995f0e381c6",  # noqa: E501
    "unitree_api/msg/RequestLease": "RIHS01_16b5c2257d5280a095e3e4fe26a48e782e294fa3d68760ce38599260a344bf4e",  # noqa: E501
    "unitree_api/msg/RequestPolicy": "RIHS01_742c3612b991be55430d1847af4afb2f119069f2e16e3a2143c6352a94ef35e4",  # noqa: E501
    "unitree_api/msg/Response": "RIHS01_5300d019bb652073e7248995c878765c68ab519bcbdbad2e2a17c81abd8888b9",  # noqa: E501
    "unitree_api/msg/ResponseHeader": "RIHS01_eba136c930271eec2fc582cfccc5948f8af3fe4431492842a03a3dacb1b0d765",  # noqa: E501
    "unitree_api/msg/ResponseStatus": "RIHS01_282afd2a97771014abb1f5aead0fd244d648d475f55a82b0c3c41232a8c527f7",  # noqa: E501
}
UNITREE_GO = {
    "unitree_go/msg/BmsState": "RIHS01_a7fe45fbbb6a908bdee78baa3b93e962ed924c143481a696f95b6911ce30b871",  # noqa: E501
    "unitree_go/msg/IMUState": "RIHS01_226772531e06ca5768dad7ae264221622e92ba1dbc7fcd7f8074351a23fe1c11",  # noqa: E501
    "unitree_go/msg/LowState": "RIHS01_db5172cac933e3cfc0e705903343eb4eea42e65e224e9d726d3e672aec0caf0f",  # noqa: E501
    "unitree_go/msg/MotorState": "RIHS01_86fb56a4f6bebcba854e9b510225e6666ef46cf4ea13355870c2dd3c3478a88c",  # noqa: E501
    "unitree_go/msg/SportModeState": "RIHS01_814b4692a904d586a0c6fe49ce344480434364d0fb410d06df2986a16e79fcd4",  # noqa: E501
    "unitree_go/msg/TimeSpec": "RIHS01_0cac3f0605af323add43e1ed3ae7fc01f7c7857f41380170b3ea3a899b28cb76",  # noqa: E501
}
PACKAGES = {"unitree_api": UNITREE_API, "unitree_go": UNITREE_GO}
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_our_definitions_hash_as_unitree_ros2s(package: str) -> None:
    msg = ROOT / "ros2" / package / "msg"
    assert computed(package, *sorted(msg.glob("*.msg"))) == PACKAGES[package]


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_the_installed_package_carries_unitree_ros2s_hashes(package: str) -> None:
    import importlib

    module = importlib.import_module(package)
    for name, expected in PACKAGES[package].items():
        hashes = installed(module.__file__ or "", package, "msg", name.rsplit("/", 1)[1])
        assert hashes[name] == expected, name


def test_a_copy_with_one_other_field_type_hashes_differently(tmp_path: Path) -> None:
    # The check can fail: a float32[3] rpy read as float64 (a plausible slip) is another type,
    # and so is every type that holds it, while the battery's is untouched.
    for file in (ROOT / "ros2" / "unitree_go" / "msg").glob("*.msg"):
        text = file.read_text()
        if file.name == "IMUState.msg":
            text = text.replace("float32[3] rpy", "float64[3] rpy")
        (tmp_path / file.name).write_text(text)
    hashes = computed("unitree_go", *sorted(tmp_path.glob("*.msg")))
    for changed in ("IMUState", "SportModeState", "LowState"):
        name = f"unitree_go/msg/{changed}"
        assert hashes[name] != UNITREE_GO[name]
    name = "unitree_go/msg/BmsState"
    assert hashes[name] == UNITREE_GO[name]


def test_dds_announces_unitree_ros2s_hashes() -> None:
    from unitree_api.msg import Request
    from unitree_go.msg import SportModeState

    client = RosClient("shadowhound_unitree_msgs_test")
    try:
        for kind, topic, name in (
            (Request, "/hash_check/api/sport/request", "unitree_api/msg/Request"),
            (SportModeState, "/hash_check/lf/sportmodestate", "unitree_go/msg/SportModeState"),
        ):
            client.publisher(kind, topic)
            info = wait_until(
                lambda topic=topic: client.node.get_publishers_info_by_topic(topic),
                10,
                f"the {topic} publisher in the graph",
            )
            expected = {**UNITREE_API, **UNITREE_GO}[name]
            assert str(info[0].topic_type_hash) == expected
    finally:
        client.close()

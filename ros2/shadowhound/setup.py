"""colcon/ament_python glue: installs the package marker, the launch file and `mission_node`.

The node's code is the `shadowhound` Python package (pip install 'shadowhound[ros]').
"""

from setuptools import setup

setup(
    name="shadowhound_ros",
    version="0.1.0",
    packages=[],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/shadowhound"]),
        ("share/shadowhound", ["package.xml"]),
        ("share/shadowhound/launch", ["launch/mission_node.launch.py"]),
    ],
    install_requires=["setuptools"],
    entry_points={"console_scripts": ["mission_node = shadowhound.ros.node:main"]},
)

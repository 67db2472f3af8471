"""The MCP desk shares the one mission worker with the other interfaces of its process: while
any interface's mission runs, an MCP mission or skill call is refused as busy, never queued."""

from __future__ import annotations

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.mcp.desk import BUSY, McpDesk, ToolInputError
from shadowhound.worker import MissionJob, MissionWorker


def _noop(_job: MissionJob) -> None:
    return None


def test_a_mission_from_another_interface_makes_mcp_busy():
    settings = ShadowHoundConfig()
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(settings.sim, time_scale=1.0),
                                        settings=settings))
    agent.initialize()
    worker = MissionWorker(agent, on_start=_noop, on_finish=_noop)  # e.g. the ROS node's
    desk = McpDesk(agent, worker=worker)
    try:
        ros_job = MissionJob("walk forward 0.3 meters", source="topic")
        assert worker.submit(ros_job) is None
        with pytest.raises(ToolInputError) as refused:
            desk.start_mission("turn left 90 degrees")
        assert str(refused.value) == BUSY
        with pytest.raises(ToolInputError, match="^busy:"):
            desk.start_skill("nav_rotate", {"degrees": 90})
        assert ros_job.done.wait(30) and ros_job.result is not None
        assert ros_job.result.success
        mcp_job = desk.start_skill("nav_rotate", {"degrees": 90})
        assert mcp_job.done.wait(30) and mcp_job.result is not None
        assert [s.skill for s in mcp_job.result.steps] == ["nav.rotate"]
        assert [r.mission for r in agent.history] == ["walk forward 0.3 meters",
                                                      "nav.rotate(degrees=90.0)"]
    finally:
        desk.close()
        worker.stop()
        agent.cleanup()

from agents.automaton import DOCKING_TIME, RETRY_AFTER, Situation, TaskAutomaton


def at(now, **kw):
    base = {"dock": "dock1", "location": "dock1", "navigation": "idle", "battery": "normal"}
    base.update(kw)
    return Situation(now=now, **base)


def test_task_in_the_space_wins():
    automaton = TaskAutomaton()
    assert automaton.step(at(0, task="Idle")).task == "Idle"
    plan = automaton.step(at(1, task="GoingToDock", location="hall", navigation="navigating"))
    assert plan.task == "GoingToDock"
    assert plan.target == "dock1"


def test_user_request_becomes_the_task_and_is_taken():
    automaton = TaskAutomaton()
    plan = automaton.step(at(0, task="Idle", requested="AttendingPatient", person_room="room_101"))
    assert plan.task == "AttendingPatient"
    assert plan.target == "room_101"
    assert plan.interacting
    assert plan.take_request


def test_power_cycle_then_back_to_the_interrupted_patient():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="AttendingPatient", location="room_101", person_room="room_101"))
    # The reasoner sends the robot to the dock (very low battery).
    plan = automaton.step(at(10, task="GoingToDock", location="room_101", battery="very low"))
    assert (plan.task, plan.target, plan.interacting) == ("GoingToDock", "dock1", False)
    assert plan.resume == "AttendingPatient"
    plan = automaton.step(at(20, task="GoingToDock", location="dock1", navigation="reached"))
    assert plan.task == "Docking"
    plan = automaton.step(at(20 + DOCKING_TIME, task="Docking", battery="very low"))
    assert plan.task == "Charging"
    assert automaton.step(at(30, task="Charging", battery="normal")).task == "Charging"
    plan = automaton.step(at(40, task="Charging", battery="full", person_room="room_101"))
    assert (plan.task, plan.target, plan.resume) == ("AttendingPatient", "room_101", None)


def test_work_requested_while_charging_waits_for_the_charge():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="Charging"))
    plan = automaton.step(at(1, task="Charging", requested="AttendingPatient"))
    assert plan.task == "Charging"
    assert plan.resume == "AttendingPatient"
    assert plan.take_request
    plan = automaton.step(at(2, task="Charging", battery="full", person_room="room_101"))
    assert plan.task == "AttendingPatient"


def test_a_patient_handed_over_while_charging_is_not_gone_back_to():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="AttendingPatient", location="room_101", person_room="room_101"))
    automaton.step(at(1, task="GoingToDock", location="room_101", battery="very low"))
    # Fleet rules gave the patient to another robot: no attended person any more.
    assert automaton.step(at(2, task="Charging", battery="full")).task == "Idle"


def test_guiding_ends_at_the_destination():
    automaton = TaskAutomaton()
    plan = automaton.step(at(0, task="Guiding", location="hall", guide_destination="therapy_room"))
    assert plan.target == "therapy_room"
    assert plan.interacting
    loc = {"location": "therapy_room", "guide_destination": "therapy_room"}
    assert automaton.step(at(5, task="Guiding", navigation="reached", **loc)).task == "Idle"


def test_aborted_guiding_is_not_resumed_after_charging():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="Guiding", location="hall", guide_destination="therapy_room"))
    automaton.step(at(1, task="GoingToDock", location="hall", navigation="navigating"))
    assert automaton.step(at(2, task="Charging", battery="full")).task == "Idle"


def test_elapsed_time_counts_from_the_task_start_and_survives_a_restart():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="Idle"))
    automaton.step(at(10, task="AttendingPatient"))
    assert automaton.step(at(25, task="AttendingPatient")).elapsed == 15
    restarted = TaskAutomaton()
    assert restarted.step(at(3, task="AttendingPatient", elapsed=15)).elapsed == 15


def test_a_restart_while_charging_still_resumes_the_interrupted_work():
    restarted = TaskAutomaton()
    plan = restarted.step(at(0, task="Charging", resume="AttendingPatient"))
    assert plan.resume == "AttendingPatient"
    plan = restarted.step(at(5, task="Charging", battery="full", person_room="room_101"))
    assert (plan.task, plan.target) == ("AttendingPatient", "room_101")


def test_a_postponed_patient_is_attended_again_once_the_robot_is_free():
    automaton = TaskAutomaton()
    automaton.step(at(0, task="AttendingPatient", person_room="room_101"))
    waiting = {"postponed": "AttendingPatient", "postponed_room": "room_102"}
    # The rules postponed the visit: the robot is idle, and stays so for a while.
    plan = automaton.step(at(600, task="Idle", **waiting))
    assert (plan.task, plan.take_postponed) == ("Idle", False)
    # A low battery, or a new request, comes first.
    plan = automaton.step(at(600 + RETRY_AFTER, task="Idle", battery="low", **waiting))
    assert (plan.task, plan.take_postponed) == ("Idle", False)
    plan = automaton.step(at(601 + RETRY_AFTER, task="Idle", battery="normal", **waiting))
    assert (plan.task, plan.target, plan.interacting) == ("AttendingPatient", "room_102", True)
    assert plan.take_postponed


def test_a_postponed_guiding_is_given_up_not_resumed():
    automaton = TaskAutomaton(retry_after=10)
    plan = automaton.step(at(0, task="Idle", postponed="Guiding", postponed_room="hall"))
    assert plan.take_postponed is False
    plan = automaton.step(at(10, task="Idle", postponed="Guiding", postponed_room="hall"))
    assert (plan.task, plan.take_postponed) == ("Idle", True)

"""Forms of the staff orders pages (server-rendered, no script needed)."""

from typing import Any

from django import forms

from maps.models import Map, Station, VehicleType
from orders.models import OrderStep, TransportOrder
from robots.models import Vehicle

STEP_ROWS = 6  # rows of the create form; blank rows are left out


class OrderFilterForm(forms.Form):
    """Narrow the list: status, a station anywhere in the order, vehicle, free text."""

    status = forms.ChoiceField(
        choices=[("", "open"), ("ALL", "all"), *TransportOrder.Status.choices], required=False
    )
    station = forms.CharField(max_length=100, required=False, label="Station")
    vehicle = forms.CharField(max_length=100, required=False, label="Vehicle serial")
    q = forms.CharField(max_length=200, required=False, label="Reference or load")


class StationChoiceField(forms.ModelChoiceField):  # type: ignore[type-arg]
    """Stations as `map/station id`, which staff read on the floor signs."""

    def label_from_instance(self, obj: Any) -> str:
        return f"{obj.map.map_id}/{obj.station_id}"


class StepForm(forms.Form):
    """One row of the multi-stop create form."""

    station = StationChoiceField(queryset=Station.objects.none(), required=False)
    operation = forms.ChoiceField(choices=OrderStep.Operation.choices, initial="PICK")
    action_type = forms.CharField(max_length=100, required=False, label="Action type")


class OrderCreateForm(forms.Form):
    """The order itself; its steps come from the `StepFormSet` beside it."""

    priority = forms.IntegerField(initial=0, min_value=-1000, max_value=1000)
    load_id = forms.CharField(max_length=100, required=False, label="Load id")
    load_type = forms.CharField(max_length=100, initial="EPAL", label="Load type")
    external_ref = forms.CharField(max_length=200, required=False, label="Reference")
    deadline = forms.DateTimeField(
        required=False, widget=forms.DateTimeInput(attrs={"type": "datetime-local"})
    )
    intended_vehicle = forms.ModelChoiceField(
        queryset=Vehicle.objects.all(), required=False, label="Only vehicle"
    )
    vehicle_type = forms.ModelChoiceField(
        queryset=VehicleType.objects.all(), required=False, label="Vehicle type"
    )


def step_formset(data: Any = None, *, layout: Map | None = None) -> Any:
    """The step rows, offering the stations of `layout` (all maps when None)."""
    formset_class = forms.formset_factory(StepForm, extra=STEP_ROWS, max_num=STEP_ROWS)
    formset = formset_class(data, prefix="step")
    stations = Station.objects.select_related("map").order_by("map__map_id", "station_id")
    if layout is not None:
        stations = stations.filter(map=layout)
    for form in formset:
        form.fields["station"].queryset = stations  # type: ignore[attr-defined]
    return formset


class PriorityForm(forms.Form):
    priority = forms.IntegerField(min_value=-1000, max_value=1000)


class ReassignForm(forms.Form):
    vehicle = forms.ModelChoiceField(
        queryset=Vehicle.objects.all(), required=False, empty_label="any vehicle"
    )


class RecurringOrderForm(forms.Form):
    """A simple A → B schedule as staff set it up on the page (admin allows any steps)."""

    name = forms.CharField(max_length=100)
    source = forms.ModelChoiceField(queryset=Station.objects.select_related("map"), label="From")
    destination = forms.ModelChoiceField(queryset=Station.objects.select_related("map"), label="To")
    interval_minutes = forms.IntegerField(min_value=1, max_value=24 * 60, initial=15)
    weekdays = forms.MultipleChoiceField(
        choices=[
            (str(i), d) for i, d in enumerate(["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"])
        ],
        initial=["0", "1", "2", "3", "4"],
        widget=forms.CheckboxSelectMultiple,
    )
    window_start = forms.TimeField(initial="06:00", widget=forms.TimeInput(attrs={"type": "time"}))
    window_end = forms.TimeField(initial="22:00", widget=forms.TimeInput(attrs={"type": "time"}))
    priority = forms.IntegerField(initial=0, min_value=-1000, max_value=1000)

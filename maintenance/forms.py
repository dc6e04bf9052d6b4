"""Forms of the maintenance pages (validation only; the services write)."""

from django import forms

from maintenance.models import WorkOrder


class AdvanceForm(forms.Form):
    status = forms.ChoiceField(choices=[c for c in WorkOrder.Status.choices if c[0] != "DUE"])
    notes = forms.CharField(required=False, widget=forms.Textarea(attrs={"rows": 3}))
    part = forms.CharField(required=False, max_length=200)
    quantity = forms.IntegerField(required=False, min_value=1, max_value=10_000)
    attachment = forms.FileField(required=False)

    def parts(self) -> list[dict[str, object]]:
        part = self.cleaned_data.get("part", "").strip()
        return [{"part": part, "qty": self.cleaned_data.get("quantity") or 1}] if part else []


class OutOfServiceForm(forms.Form):
    reason = forms.CharField(max_length=200)
    send_to = forms.ChoiceField(
        required=False,
        choices=[("", "stay where it is"), ("PARK", "a park station"), ("OTHER", "a service bay")],
    )


class NewWorkOrderForm(forms.Form):
    title = forms.CharField(max_length=200)
    takes_out_of_service = forms.BooleanField(required=False)
    notes = forms.CharField(required=False, widget=forms.Textarea(attrs={"rows": 3}))

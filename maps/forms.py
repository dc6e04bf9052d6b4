"""Forms of the layout pages."""

from django import forms

from maps.models import Map


class NewMapForm(forms.Form):
    """A new, empty map to draw in the layout editor."""

    map_id = forms.SlugField(
        max_length=100, label="Map id", help_text="the mapId vehicles know the map by"
    )
    name = forms.CharField(max_length=200)
    site = forms.SlugField(max_length=100, required=False, help_text="optional; created if missing")
    level = forms.CharField(max_length=100, required=False, help_text="floor within the site")

    def clean_map_id(self) -> str:
        map_id: str = self.cleaned_data["map_id"]
        if Map.objects.filter(map_id=map_id).exists():
            raise forms.ValidationError(f"a map {map_id} exists already")
        return map_id

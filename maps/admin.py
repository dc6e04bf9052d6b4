"""Admin for sites, maps, LIF imports and layouts, vehicle types, nodes, edges, stations, zones.

Every change of the graph made here goes through `maps.services.mark_layout_changed`, so routing
caches see it.
"""

import json
from collections.abc import Iterable
from typing import Any

from django import forms
from django.contrib import admin, messages
from django.db.models import Model, QuerySet
from django.http import HttpRequest, HttpResponse, HttpResponseRedirect
from django.template.response import TemplateResponse
from django.urls import URLPattern, path, reverse
from django.utils.html import format_html

from fleet.exceptions import InvalidRequestError
from maps.lif.export import export_lif
from maps.models import (
    Edge,
    EdgeProperty,
    Layout,
    LifImport,
    Map,
    MapRelease,
    MapVersion,
    Node,
    NodeProperty,
    Site,
    Station,
    StationNode,
    VehicleType,
    Zone,
)
from maps.selectors import validate_layout
from maps.services import (
    distribute_release,
    import_lif,
    mark_layout_changed,
    release_map,
    set_zones_enabled,
)
from maps.services.zones import counter_clockwise

MAX_FINDING_MESSAGES = 20


class LayoutChangeAdmin(admin.ModelAdmin[Any]):
    """Marks the map of every saved or deleted row as changed (for routing caches)."""

    def maps_of(self, objects: Iterable[Model]) -> list[Map]:
        return [obj.map for obj in objects if getattr(obj, "map_id", None)]  # type: ignore[attr-defined]

    def save_related(self, request: HttpRequest, form: Any, formsets: Any, change: bool) -> None:
        super().save_related(request, form, formsets, change)
        mark_layout_changed(maps=self.maps_of([form.instance]))

    def delete_model(self, request: HttpRequest, obj: Any) -> None:
        maps = self.maps_of([obj])
        super().delete_model(request, obj)
        mark_layout_changed(maps=maps)

    def delete_queryset(self, request: HttpRequest, queryset: QuerySet[Any]) -> None:
        maps = self.maps_of(queryset)
        super().delete_queryset(request, queryset)
        mark_layout_changed(maps=maps)


class MapInline(admin.TabularInline[Map, Site]):
    model = Map
    fields = ["map_id", "name", "level"]
    show_change_link = True
    extra = 0


@admin.register(Site)
class SiteAdmin(admin.ModelAdmin[Site]):
    list_display = ["site_id", "name"]
    search_fields = ["site_id", "name"]
    inlines = [MapInline]


class MapVersionInline(admin.TabularInline[MapVersion, Map]):
    """The versions saved in the layout editor, newest first (read only)."""

    model = MapVersion
    fields = ["number", "saved_at", "saved_by", "note", "counts", "revision"]
    readonly_fields = ["number", "saved_at", "saved_by", "note", "counts", "revision"]
    extra = 0
    max_num = 0
    can_delete = False
    ordering = ["-number"]


@admin.register(Map)
class MapAdmin(admin.ModelAdmin[Map]):
    list_display = ["map_id", "name", "site", "level", "version", "revision", "editor_link"]
    list_filter = ["site"]
    search_fields = ["map_id", "name"]
    readonly_fields = ["revision", "version", "lif_import", "source_id"]
    actions = ["validate", "export", "release_and_distribute"]
    change_form_template = "admin/maps/map/change_form.html"
    inlines = [MapVersionInline]
    fieldsets = [
        (None, {"fields": ["map_id", "name", "description", "site", "level"]}),
        (
            "Floor plan",
            {
                "fields": [
                    "floor_plan",
                    "floor_plan_scale",
                    "floor_plan_origin_x",
                    "floor_plan_origin_y",
                    "floor_plan_rotation",
                ]
            },
        ),
        ("Origin", {"fields": ["lif_import", "source_id", "revision", "version"]}),
    ]

    @admin.display(description="layout editor")
    def editor_link(self, obj: Map) -> str:
        return format_html('<a href="{}">edit layout</a>', reverse("maps:edit", args=[obj.pk]))

    @admin.action(description="Validate the selected maps")
    def validate(self, request: HttpRequest, queryset: QuerySet[Map]) -> None:
        for layout in queryset:
            findings = validate_layout(map=layout)
            errors = sum(f.severity == "error" for f in findings)
            level = messages.ERROR if errors else messages.SUCCESS
            summary = f"{layout.map_id}: {errors} error(s), {len(findings) - errors} warning(s)"
            self.message_user(request, summary, level)
            for finding in findings[:MAX_FINDING_MESSAGES]:
                severe = finding.severity == "error"
                self.message_user(
                    request, str(finding), messages.ERROR if severe else messages.WARNING
                )

    @admin.action(description="Release the selected maps as files for the vehicles and distribute")
    def release_and_distribute(self, request: HttpRequest, queryset: QuerySet[Map]) -> None:
        for layout in queryset:
            try:
                release = release_map(map=layout, user=request.user, distribute=True)
            except InvalidRequestError as exc:
                self.message_user(request, f"{layout.map_id}: {exc}", messages.ERROR)
                continue
            self.message_user(request, f"released and distributing {release}", messages.SUCCESS)

    @admin.action(description="Export the selected maps as a LIF file")
    def export(self, request: HttpRequest, queryset: QuerySet[Map]) -> HttpResponse:
        maps = list(queryset.select_related("site", "lif_import"))
        name = maps[0].map_id if len(maps) == 1 else "layout"
        response = HttpResponse(
            json.dumps(export_lif(maps=maps), indent=2), content_type="application/json"
        )
        response["Content-Disposition"] = f'attachment; filename="{name}.lif.json"'
        return response


class LifUploadForm(forms.Form):
    """The admin's LIF upload: the file, the site it goes to, whether to replace."""

    file = forms.FileField(help_text="a LIF 1.0 JSON file")
    site = forms.CharField(max_length=100, initial="default", help_text="created if missing")
    replace = forms.BooleanField(
        required=False, help_text="replace an earlier import of the same project"
    )


@admin.register(LifImport)
class LifImportAdmin(admin.ModelAdmin[LifImport]):
    list_display = ["project", "site", "lif_version", "prefix", "file_name", "imported_at"]
    list_filter = ["site"]
    readonly_fields = [f.name for f in LifImport._meta.fields]

    def get_urls(self) -> list[URLPattern]:
        upload = path("upload/", self.admin_site.admin_view(self.upload), name="maps_lif_upload")
        return [upload, *super().get_urls()]

    def add_view(self, request: HttpRequest, *args: Any, **kwargs: Any) -> HttpResponse:
        return HttpResponseRedirect(reverse("admin:maps_lif_upload"))

    def upload(self, request: HttpRequest) -> HttpResponse:
        """Upload a LIF file; shows the import report (every problem when nothing was written)."""
        if not self.has_add_permission(request):
            return HttpResponseRedirect(reverse("admin:index"))
        form = LifUploadForm(request.POST or None, request.FILES or None)
        report = None
        if request.method == "POST" and form.is_valid():
            upload = form.cleaned_data["file"]
            report = import_lif(
                source=upload.read(),
                site_id=form.cleaned_data["site"],
                replace=form.cleaned_data["replace"],
                file_name=upload.name or "",
            )
        context = {
            **self.admin_site.each_context(request),
            "opts": self.model._meta,
            "title": "Import a LIF file",
            "form": form,
            "report": report,
        }
        return TemplateResponse(request, "admin/maps/lifimport/upload.html", context)


@admin.register(Layout)
class LayoutAdmin(admin.ModelAdmin[Layout]):
    list_display = ["layout_id", "name", "site", "version", "level_id", "lif_import"]
    list_filter = ["site"]
    search_fields = ["layout_id", "name"]


@admin.register(VehicleType)
class VehicleTypeAdmin(admin.ModelAdmin[VehicleType]):
    list_display = ["type_id", "name", "max_speed", "rotation_speed", "height"]
    search_fields = ["type_id", "name", "manufacturer", "series_name"]


class NodePropertyInline(admin.TabularInline[NodeProperty, Node]):
    model = NodeProperty
    extra = 0


@admin.register(Node)
class NodeAdmin(LayoutChangeAdmin):
    list_display = ["node_id", "map", "x", "y", "theta", "layout"]
    list_filter = ["map"]
    search_fields = ["node_id", "name"]
    raw_id_fields = ["layout"]
    inlines = [NodePropertyInline]


class EdgePropertyInline(admin.StackedInline[EdgeProperty, Edge]):
    model = EdgeProperty
    extra = 0


@admin.register(Edge)
class EdgeAdmin(LayoutChangeAdmin):
    list_display = ["edge_id", "map", "start", "end", "length", "max_speed"]
    list_filter = ["map"]
    search_fields = ["edge_id", "name"]
    raw_id_fields = ["start", "end", "layout"]
    inlines = [EdgePropertyInline]


class StationNodeInline(admin.TabularInline[StationNode, Station]):
    model = StationNode
    raw_id_fields = ["node"]
    extra = 0


@admin.register(Station)
class StationAdmin(LayoutChangeAdmin):
    list_display = ["station_id", "name", "kind", "map", "node"]
    list_filter = ["map", "kind"]
    search_fields = ["station_id", "name"]
    raw_id_fields = ["node", "layout"]
    inlines = [StationNodeInline]


@admin.register(Zone)
class ZoneAdmin(LayoutChangeAdmin):
    """Zones: vertices as JSON here (drawn in the layout editor); the form checks type rules."""

    list_display = ["zone_id", "name", "map", "zone_type", "enabled", "max_speed"]
    list_filter = ["map", "zone_type", "enabled"]
    search_fields = ["zone_id", "name"]
    filter_horizontal = ["vehicle_types"]
    actions = ["enable", "disable"]
    fieldsets = [
        (None, {"fields": ["map", "zone_id", "name", "description", "zone_type", "enabled"]}),
        ("Shape", {"fields": ["vertices"]}),
        (
            "What the zone does (by type)",
            {
                "fields": [
                    "max_speed",
                    "direction",
                    "limitation",
                    "penalty_factor",
                    "priority_factor",
                    "release_loss_behavior",
                    "vehicle_types",
                    "entry_actions",
                    "during_actions",
                    "exit_actions",
                ]
            },
        ),
    ]

    def save_model(self, request: HttpRequest, obj: Zone, form: Any, change: bool) -> None:
        obj.vertices = counter_clockwise(obj.vertices)  # the form's clean() checked them
        super().save_model(request, obj, form, change)

    @admin.action(description="Enable the selected zones")
    def enable(self, request: HttpRequest, queryset: QuerySet[Zone]) -> None:
        count = set_zones_enabled(zones=queryset.select_related("map"), enabled=True)
        self.message_user(request, f"{count} zone(s) enabled", messages.SUCCESS)

    @admin.action(description="Disable the selected zones")
    def disable(self, request: HttpRequest, queryset: QuerySet[Zone]) -> None:
        count = set_zones_enabled(zones=queryset.select_related("map"), enabled=False)
        self.message_user(request, f"{count} zone(s) disabled", messages.SUCCESS)


@admin.register(MapRelease)
class MapReleaseAdmin(admin.ModelAdmin[MapRelease]):
    """Released map files; release from the map list, distribute here (REFERENCE K.47)."""

    list_display = ["map", "version", "checksum_short", "size", "created_at", "distributed_at"]
    list_filter = ["map"]
    readonly_fields = [
        "map",
        "number",
        "version",
        "file_format",
        "checksum",
        "size",
        "revision",
        "created_at",
        "created_by",
        "distributed_at",
        "distributed_by",
        "download_link",
    ]
    fields = [*readonly_fields, "note"]
    actions = ["distribute"]

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False  # releases come from the map list's action (release_map)

    @admin.display(description="checksum")
    def checksum_short(self, obj: MapRelease) -> str:
        return obj.checksum[:12]

    @admin.display(description="file")
    def download_link(self, obj: MapRelease) -> str:
        url = reverse("maps:release-file", args=[obj.token, obj.file_name])
        return format_html('<a href="{}">{}</a>', url, obj.file_name)

    @admin.action(description="Distribute the selected release to the vehicles")
    def distribute(self, request: HttpRequest, queryset: QuerySet[MapRelease]) -> None:
        releases = list(queryset.select_related("map"))
        if len({r.map_id for r in releases}) != len(releases):
            self.message_user(request, "choose at most one release per map", messages.ERROR)
            return
        for release in releases:
            distribute_release(release=release, user=request.user)
            self.message_user(request, f"{release}: distributing to the vehicles", messages.SUCCESS)

"""Admin of the battery app: chargers and policies are edited here; sessions, history and
alerts are read-only records."""

from django.contrib import admin

from battery.models import (
    BatteryAlert,
    BatterySample,
    Charger,
    ChargeSession,
    ChargingPolicy,
    VehicleEnergy,
)


@admin.register(Charger)
class ChargerAdmin(admin.ModelAdmin[Charger]):
    list_display = ["station", "capacity", "is_active"]
    list_filter = ["is_active"]
    filter_horizontal = ["vehicle_types"]
    list_select_related = ["station"]

    def formfield_for_foreignkey(self, db_field, request, **kwargs):  # type: ignore[no-untyped-def]
        if db_field.name == "station":
            from maps.models import Station

            kwargs["queryset"] = Station.objects.filter(kind=Station.Kind.CHARGE)
        return super().formfield_for_foreignkey(db_field, request, **kwargs)


@admin.register(ChargingPolicy)
class ChargingPolicyAdmin(admin.ModelAdmin[ChargingPolicy]):
    list_display = [
        "__str__",
        "critical",
        "needs_charge",
        "sufficient",
        "charge_until",
        "full",
        "opportunity_charging",
        "shift_reserve_hours",
    ]


class ReadOnly:
    def has_add_permission(self, request, obj=None) -> bool:  # type: ignore[no-untyped-def]
        return False

    def has_change_permission(self, request, obj=None) -> bool:  # type: ignore[no-untyped-def]
        return False


@admin.register(ChargeSession)
class ChargeSessionAdmin(ReadOnly, admin.ModelAdmin[ChargeSession]):
    list_display = [
        "__str__",
        "vehicle",
        "charger",
        "point",
        "status",
        "reason",
        "start_charge",
        "end_charge",
        "created_at",
        "ended_at",
    ]
    list_filter = ["status", "reason", "charger"]
    list_select_related = ["vehicle", "charger__station"]


@admin.register(VehicleEnergy)
class VehicleEnergyAdmin(ReadOnly, admin.ModelAdmin[VehicleEnergy]):
    list_display = [
        "vehicle",
        "drain_per_metre",
        "drain_per_hour",
        "charge_cycles",
        "health",
        "updated_at",
    ]
    list_select_related = ["vehicle"]


@admin.register(BatterySample)
class BatterySampleAdmin(ReadOnly, admin.ModelAdmin[BatterySample]):
    list_display = ["vehicle", "at", "charge", "charging", "drain_per_metre"]
    list_filter = ["charging"]
    date_hierarchy = "at"
    list_select_related = ["vehicle"]


@admin.register(BatteryAlert)
class BatteryAlertAdmin(ReadOnly, admin.ModelAdmin[BatteryAlert]):
    list_display = ["vehicle", "level", "charge", "raised_at", "resolved_at"]
    list_filter = ["level"]
    list_select_related = ["vehicle"]

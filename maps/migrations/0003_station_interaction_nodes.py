"""Every existing station gets its node as its first (primary) interaction node."""

from django.db import migrations


def primary_interaction_nodes(apps, schema_editor):
    Station = apps.get_model("maps", "Station")
    StationNode = apps.get_model("maps", "StationNode")
    StationNode.objects.bulk_create(
        StationNode(station_id=pk, node_id=node_id, position=0)
        for pk, node_id in Station.objects.values_list("pk", "node_id")
    )


class Migration(migrations.Migration):
    dependencies = [("maps", "0002_sites_lif_vehicle_types")]

    operations = [migrations.RunPython(primary_interaction_nodes, migrations.RunPython.noop)]
